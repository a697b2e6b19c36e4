#pragma once
// The bytes of checkpoints. Each class whose state carries from one step to the next writes and
// reads its part with one pair, save(CheckpointWriter&) / restore(CheckpointReader&)
// (RigidContactSolver, SurfaceContactSet), and a checkpoint in memory keeps those bytes: a file
// (bullet/checkpoint_io.h) holds the same bytes, so the two can never disagree.
//
// Numbers are little-endian; a rigid object is its index among the Bullet world's collision
// objects. Reads are checked: bytes cut short, or values no save writes, make the reader fail,
// and its error() names the section it was reading (section()), never reading out of bounds.

#include <BulletCollision/CollisionDispatch/btCollisionObject.h>
#include <LinearMath/btAlignedObjectArray.h>

#include <Eigen/Core>
#include <cstdint>
#include <cstring>
#include <string>
#include <string_view>
#include <type_traits>
#include <vector>

#include "torsion/result.h"

#if defined(__BYTE_ORDER__)
static_assert(__BYTE_ORDER__ == __ORDER_LITTLE_ENDIAN__, "checkpoint bytes are little-endian");
#endif

namespace torsion {

class CheckpointWriter {
 public:
  template <typename T>
  void raw(T value) {
    static_assert(std::is_arithmetic_v<T>);
    char bytes[sizeof(T)];
    std::memcpy(bytes, &value, sizeof(T));
    out_.append(bytes, sizeof(T));
  }
  void u8(int v) { raw(static_cast<std::uint8_t>(v)); }
  void u32(size_t v) { raw(static_cast<std::uint32_t>(v)); }
  void i32(int v) { raw(static_cast<std::int32_t>(v)); }
  void i64(std::int64_t v) { raw(v); }
  void f64(double v) { raw(v); }
  void str(std::string_view s) {
    u32(s.size());
    out_.append(s.data(), s.size());
  }
  void vec3(const Eigen::Vector3d& v) {
    for (int k = 0; k < 3; ++k)
      f64(v[k]);
  }
  void vector(const Eigen::VectorXd& v) {
    u32(static_cast<size_t>(v.size()));
    for (Eigen::Index k = 0; k < v.size(); ++k)
      f64(v[k]);
  }
  void ints(const std::vector<int>& v) {
    u32(v.size());
    for (int x : v)
      i32(x);
  }
  /// A collision object by its index in its world's array (Bullet keeps the index in the object:
  /// no search), -1 for none.
  void object(const btCollisionObject* object) {
    i32(object != nullptr ? object->getWorldArrayIndex() : -1);
  }
  std::string& bytes() { return out_; }

 private:
  std::string out_;
};

// The first failure sticks and later reads return zeros, so a reader can parse on and check ok()
// where a wrong value would do harm.
class CheckpointReader {
 public:
  /// `objects`: the world's collision objects, which object() reads indices into (none: every
  /// object read is refused).
  explicit CheckpointReader(std::string_view bytes, const btCollisionObjectArray* objects = nullptr)
      : in_(bytes), objects_(objects) {}

  bool ok() const { return ok_; }
  bool atEnd() const { return at_ == in_.size(); }
  /// What the reads that follow read, for error(): "body 'cube': its rigid contacts". A failure
  /// keeps the section it happened in.
  void section(std::string what) {
    if (ok_) section_ = std::move(what);
  }
  /// A value no save writes (crafted bytes behind a valid hash, or a writer's bug): `why`
  /// describes it. The first one is kept.
  void refuse(const std::string& why) {
    if (ok_ && invalid_.empty()) invalid_ = why;
    ok_ = false;
  }
  /// Bytes that cannot be what a save wrote here (cut short, or a count or index out of range).
  void fail() { ok_ = false; }
  /// Why the reads failed, naming the section: a value no save writes, or bytes cut short.
  Error error() const {
    const std::string where = section_.empty() ? "" : " (reading " + section_ + ")";
    if (!invalid_.empty())
      return Error{"the checkpoint holds an invalid value: " + invalid_ + where};
    return Error{"the checkpoint is truncated or corrupted" + where};
  }
  /// Ok, or error().
  Status status() const {
    if (ok_) return Ok{};
    return error();
  }

  template <typename T>
  T raw() {
    T value{};
    if (!take(sizeof(T))) return value;
    std::memcpy(&value, in_.data() + at_ - sizeof(T), sizeof(T));
    return value;
  }
  int u8() { return raw<std::uint8_t>(); }
  size_t u32() { return raw<std::uint32_t>(); }
  int i32() { return raw<std::int32_t>(); }
  std::int64_t i64() { return raw<std::int64_t>(); }
  double f64() { return raw<double>(); }
  /// A count of items of at least `item_size` bytes each: no more than the bytes left hold.
  size_t count(size_t item_size) {
    const size_t n = u32();
    if (n * item_size > in_.size() - at_) ok_ = false;
    return ok_ ? n : 0;
  }
  std::string str() {
    const size_t n = count(1);
    if (!take(n)) return {};
    return std::string(in_.substr(at_ - n, n));
  }
  Eigen::Vector3d vec3() {
    Eigen::Vector3d v;
    for (int k = 0; k < 3; ++k)
      v[k] = f64();
    return v;
  }
  Eigen::VectorXd vector() {
    Eigen::VectorXd v(static_cast<Eigen::Index>(count(8)));
    for (Eigen::Index k = 0; k < v.size(); ++k)
      v[k] = f64();
    return v;
  }
  std::vector<int> ints() {
    std::vector<int> v(count(4));
    for (int& x : v)
      x = i32();
    return v;
  }
  /// An enum stored as u8, at most `last`.
  template <typename E>
  E enumeration(E last) {
    const int v = u8();
    if (v > static_cast<int>(last)) ok_ = false;
    return static_cast<E>(ok_ ? v : 0);
  }
  /// A collision object of the world, written by CheckpointWriter::object (never null when ok).
  const btCollisionObject* object() {
    const int index = i32();
    const int count = objects_ != nullptr ? objects_->size() : 0;
    if (!ok_) return nullptr;
    if (index < 0 || index >= count) {
      refuse("rigid object " + std::to_string(index) + " (the world has " + std::to_string(count) +
             " collision objects)");
      return nullptr;
    }
    return (*objects_)[index];
  }

 private:
  bool take(size_t n) {
    if (!ok_ || n > in_.size() - at_) {
      ok_ = false;
      return false;
    }
    at_ += n;
    return true;
  }
  std::string_view in_;
  const btCollisionObjectArray* objects_;
  std::string section_;
  std::string invalid_;
  size_t at_ = 0;
  bool ok_ = true;
};

}  // namespace torsion
