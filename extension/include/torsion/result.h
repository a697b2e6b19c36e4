#pragma once
// Error values for bad input (files, scenes, settings). Programmer mistakes are asserts; run-time
// trouble in a simulation is a status flag; only input the user can fix comes back as an Error.

#include <stdexcept>
#include <string>
#include <utility>
#include <variant>

namespace torsion {

/// A message meant for the user. By convention it starts with where the fault is
/// ("cyl.ele:118: tet 116: ...") and names the fault and the sizes involved.
struct Error {
  std::string message;
};

/// Thrown by Result::value() on a Result holding an Error: what() is the Error's message, so
/// `attach(world).value()` on a failure stops with the reason (also uncaught: std::terminate
/// prints what()).
class BadResultAccess : public std::runtime_error {
 public:
  explicit BadResultAccess(const Error& error) : std::runtime_error(error.message) {}
};

/// Either a value or an Error. Small on purpose: no monadic chaining, just ok()/value()/error().
/// value() on an Error throws BadResultAccess carrying its message.
template <class T>
class [[nodiscard]] Result {
 public:
  Result(T value)
      : state_(std::in_place_index<0>, std::move(value)) {}  // NOLINT: implicit by design
  Result(Error error) : state_(std::in_place_index<1>, std::move(error)) {}  // NOLINT

  bool ok() const { return state_.index() == 0; }
  explicit operator bool() const { return ok(); }

  T& value() & {
    checkValue();
    return std::get<0>(state_);
  }
  const T& value() const& {
    checkValue();
    return std::get<0>(state_);
  }
  T&& value() && {
    checkValue();
    return std::get<0>(std::move(state_));
  }

  const Error& error() const { return std::get<1>(state_); }

 private:
  void checkValue() const {
    if (!ok()) throw BadResultAccess(std::get<1>(state_));
  }

  std::variant<T, Error> state_;
};

/// For operations that return nothing but can fail.
struct Ok {};
using Status = Result<Ok>;

}  // namespace torsion
