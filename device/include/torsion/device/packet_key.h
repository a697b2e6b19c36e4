#pragma once
// The shared secret that authenticates network-device packets (docs/haptic-devices.md,
// "Authentication"). With a key, every packet carries an HMAC-SHA256 (libsodium) over its header
// and payload; the device and its peer both hold the same key and drop whatever does not verify.
//
// The key never comes from the command line (other local users can read a process's arguments):
// it is read from a file, or from the environment:
//   TORSION_HAPTIC_KEY_FILE  path of a file holding the secret
//   TORSION_HAPTIC_KEY       the secret itself
// The secret is the file's bytes (or the variable's value) less trailing whitespace, at least
// kMinKeyBytes long: e.g. `openssl rand -hex 32 > haptic.key` (64 characters, 256 bits). A key
// file must be a regular file that other users cannot read or write (chmod 600).

#include <array>
#include <cstddef>
#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "torsion/device/loaded.h"

namespace torsion::device {

inline constexpr std::size_t kMinKeyBytes = 32;
inline constexpr std::size_t kMacBytes = 32;  ///< HMAC-SHA256
inline constexpr const char* kKeyFileVariable = "TORSION_HAPTIC_KEY_FILE";
inline constexpr const char* kKeyVariable = "TORSION_HAPTIC_KEY";

using Mac = std::array<unsigned char, kMacBytes>;

class PacketKey {
 public:
  /// Reads the secret from `path`. Errors name the file: missing, unreadable, not a regular file,
  /// readable by other users, shorter than kMinKeyBytes.
  static Loaded<PacketKey> fromFile(const std::string& path);
  /// `secret` as given (less trailing whitespace); `origin` names it in errors.
  static Loaded<PacketKey> fromSecret(const std::string& secret, const std::string& origin);
  /// TORSION_HAPTIC_KEY_FILE, else TORSION_HAPTIC_KEY; an empty optional when neither is set.
  static Loaded<std::optional<PacketKey>> fromEnvironment();

  PacketKey(const PacketKey&) = default;
  PacketKey& operator=(const PacketKey&) = default;
  ~PacketKey();  ///< wipes the secret

  /// HMAC-SHA256 of `size` bytes.
  Mac mac(const unsigned char* bytes, std::size_t size) const;
  /// Constant-time comparison of `mac` with the MAC of `size` bytes.
  bool verify(const unsigned char* mac, const unsigned char* bytes, std::size_t size) const;

 private:
  explicit PacketKey(std::vector<unsigned char> secret) : secret_(std::move(secret)) {}
  std::vector<unsigned char> secret_;
};

/// A random, non-zero 64-bit number from the system's CSPRNG (libsodium's randombytes, which
/// reads getrandom(2) on Linux): the nonces that bind a signed session (udp_packet.h).
std::uint64_t randomNonce();

}  // namespace torsion::device
