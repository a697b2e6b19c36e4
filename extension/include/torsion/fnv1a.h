#pragma once
// FNV-1a, 64 bits (Fowler, Noll, Vo; the parameters of the IETF draft "The FNV Non-Cryptographic
// Hash Algorithm"): the checksum of checkpoint bytes and the run's final state hash. Not a
// defence against tampering, only against torn or corrupted bytes.

#include <cstddef>
#include <cstdint>
#include <string_view>

namespace torsion {

class Fnv1a {
 public:
  static constexpr std::uint64_t kOffsetBasis = 14695981039346656037ull;
  static constexpr std::uint64_t kPrime = 1099511628211ull;

  void add(const void* data, std::size_t n) {
    const auto* p = static_cast<const unsigned char*>(data);
    for (std::size_t i = 0; i < n; ++i) {
      hash_ ^= p[i];
      hash_ *= kPrime;
    }
  }
  void add(std::string_view bytes) { add(bytes.data(), bytes.size()); }
  void add(double value) { add(&value, sizeof value); }
  std::uint64_t value() const { return hash_; }

 private:
  std::uint64_t hash_ = kOffsetBasis;
};

/// The hash of `bytes` in one call.
inline std::uint64_t fnv1a(std::string_view bytes) {
  Fnv1a h;
  h.add(bytes);
  return h.value();
}

}  // namespace torsion
