#include "torsion/device/packet_key.h"

#include <sodium.h>
#include <sys/stat.h>

#include <cerrno>
#include <cstdlib>
#include <cstring>

#include "torsion/device/file_io.h"

namespace torsion::device {

namespace {

bool sodiumReady() {
  static const bool ready = sodium_init() >= 0;  // thread-safe, idempotent
  return ready;
}

std::string trimmedRight(std::string text) {
  while (!text.empty() &&
         (text.back() == '\n' || text.back() == '\r' || text.back() == ' ' || text.back() == '\t'))
    text.pop_back();
  return text;
}

}  // namespace

Loaded<PacketKey> PacketKey::fromSecret(const std::string& secret, const std::string& origin) {
  const std::string trimmed = trimmedRight(secret);
  if (trimmed.size() < kMinKeyBytes) {
    return Loaded<PacketKey>::fail(origin + ": the key has " + std::to_string(trimmed.size()) +
                                   " bytes, fewer than the " + std::to_string(kMinKeyBytes) +
                                   " required (make one with: openssl rand -hex 32)");
  }
  if (!sodiumReady()) return Loaded<PacketKey>::fail(origin + ": libsodium failed to initialise");
  return Loaded<PacketKey>{PacketKey(std::vector<unsigned char>(trimmed.begin(), trimmed.end())),
                           {}};
}

Loaded<PacketKey> PacketKey::fromFile(const std::string& path) {
  const std::string origin = "key file " + path;
  struct stat info {};
  if (::stat(path.c_str(), &info) != 0)
    return Loaded<PacketKey>::fail(origin + ": cannot open: " + std::strerror(errno));
  if (S_ISREG(info.st_mode) && (info.st_mode & (S_IRWXG | S_IRWXO)) != 0) {
    // As ssh does with private keys: a secret others can read is no secret.
    return Loaded<PacketKey>::fail(origin +
                                   ": other users can access it; restrict it with chmod 600");
  }
  std::string text;
  if (std::string error = readRegularFile(path, text); !error.empty())
    return Loaded<PacketKey>::fail("key file " + error);
  Loaded<PacketKey> key = fromSecret(text, origin);
  sodium_memzero(text.data(), text.size());
  return key;
}

Loaded<std::optional<PacketKey>> PacketKey::fromEnvironment() {
  using Out = Loaded<std::optional<PacketKey>>;
  if (const char* file = std::getenv(kKeyFileVariable); file && *file) {
    Loaded<PacketKey> key = fromFile(file);
    if (!key) return Out::fail(key.error + " (from " + kKeyFileVariable + ")");
    return Out{std::optional<PacketKey>(std::move(*key.value)), {}};
  }
  if (const char* secret = std::getenv(kKeyVariable); secret && *secret) {
    Loaded<PacketKey> key = fromSecret(secret, kKeyVariable);
    if (!key) return Out::fail(key.error);
    return Out{std::optional<PacketKey>(std::move(*key.value)), {}};
  }
  return Out{std::optional<PacketKey>(), {}};
}

PacketKey::~PacketKey() {
  if (!secret_.empty()) sodium_memzero(secret_.data(), secret_.size());
}

Mac PacketKey::mac(const unsigned char* bytes, std::size_t size) const {
  crypto_auth_hmacsha256_state state;
  crypto_auth_hmacsha256_init(&state, secret_.data(), secret_.size());
  crypto_auth_hmacsha256_update(&state, bytes, size);
  Mac out{};
  crypto_auth_hmacsha256_final(&state, out.data());
  sodium_memzero(&state, sizeof state);
  return out;
}

bool PacketKey::verify(const unsigned char* mac_bytes, const unsigned char* bytes,
                       std::size_t size) const {
  const Mac expected = mac(bytes, size);
  return sodium_memcmp(expected.data(), mac_bytes, kMacBytes) == 0;
}

std::uint64_t randomNonce() {
  sodiumReady();
  std::uint64_t id = 0;
  while (id == 0)
    randombytes_buf(&id, sizeof id);  // 0 means "none yet"
  return id;
}

}  // namespace torsion::device
