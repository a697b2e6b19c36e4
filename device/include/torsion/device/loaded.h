#pragma once
// A value read from a file, or the message that says why not ("path: key 'segments[2].duration':
// must be positive"). The device layer's small twin of torsion::Result (it depends on nothing).

#include <optional>
#include <string>
#include <utility>

namespace torsion::device {

template <class T>
struct [[nodiscard]] Loaded {
  std::optional<T> value;
  std::string error;  ///< set when value is empty

  static Loaded fail(std::string message) { return Loaded{std::nullopt, std::move(message)}; }
  explicit operator bool() const { return value.has_value(); }
};

}  // namespace torsion::device
