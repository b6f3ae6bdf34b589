#include "runtime/loop/model_signature.h"

#include <fcntl.h>
#include <unistd.h>

#include <cerrno>
#include <cstdio>
#include <cstring>

#include "runtime/base/file_io.h"

#if defined(APRT_HAVE_SODIUM)
#include <sodium.h>
#endif

namespace aprt {
namespace {

constexpr const char* kPublicTag = "aprt-ed25519-public-key";
constexpr const char* kSecretTag = "aprt-ed25519-secret-key";
constexpr const char* kSignatureTag = "aprt-ed25519-signature";

std::string hex(const uint8_t* p, size_t n) {
  static const char* d = "0123456789abcdef";
  std::string s;
  for (size_t i = 0; i < n; ++i) {
    s += d[p[i] >> 4];
    s += d[p[i] & 15];
  }
  return s;
}

bool unhex(const std::string& s, uint8_t* out, size_t n) {
  if (s.size() != 2 * n) return false;
  auto v = [](char c) -> int {
    if (c >= '0' && c <= '9') return c - '0';
    if (c >= 'a' && c <= 'f') return c - 'a' + 10;
    if (c >= 'A' && c <= 'F') return c - 'A' + 10;
    return -1;
  };
  for (size_t i = 0; i < n; ++i) {
    const int hi = v(s[2 * i]), lo = v(s[2 * i + 1]);
    if (hi < 0 || lo < 0) return false;
    out[i] = uint8_t(hi * 16 + lo);
  }
  return true;
}

// The first line of a small text file, split into words.
Expected<std::string> first_line(const std::string& path, const char* what) {
  // A key or signature file is one short line: a regular file of at most 4 KiB.
  std::string text;
  if (Status s = read_input_file(path.c_str(), 4096, what, &text); !s) return s.error();
  if (text.empty()) return Error(Errc::kInvalidArgument, "%s: '%s' is empty", what, path.c_str());
  std::string line = text.substr(0, text.find('\n'));
  while (!line.empty() && (line.back() == '\n' || line.back() == '\r')) line.pop_back();
  return line;
}

// "TAG HEX" or "TAG HEX key ID": the hex field after `tag`, or an error naming the file.
Expected<std::string> field_after(const std::string& line, const char* tag, const std::string& path,
                                  const char* what) {
  const std::string t = std::string(tag) + " ";
  if (line.compare(0, t.size(), t) != 0) {
    return Error(Errc::kInvalidArgument, "%s: '%s' does not start with '%s' (not an aprt %s file)",
                 what, path.c_str(), tag, what);
  }
  const size_t end = line.find(' ', t.size());
  return line.substr(t.size(), end == std::string::npos ? std::string::npos : end - t.size());
}

Status write_text(const std::string& path, const std::string& text, int mode, bool exclusive) {
  const int fd =
      open(path.c_str(), O_WRONLY | O_CREAT | O_CLOEXEC | (exclusive ? O_EXCL : O_TRUNC), mode);
  if (fd < 0) {
    return Error(Errc::kIo, "sign: cannot create '%s': %s", path.c_str(), std::strerror(errno));
  }
  const bool ok_write = write(fd, text.data(), text.size()) == ssize_t(text.size());
  const bool ok_close = close(fd) == 0;
  if (!ok_write || !ok_close) return Error(Errc::kIo, "sign: cannot write '%s'", path.c_str());
  return ok();
}

#if defined(APRT_HAVE_SODIUM)
bool sodium_ready() {
  static const bool ready = sodium_init() >= 0;
  return ready;
}
#endif

Error unavailable() {
  return Error(Errc::kUnsupported,
               "model signing: this build has no libsodium (install libsodium-dev and rebuild)");
}

}  // namespace

bool model_signing_available() {
#if defined(APRT_HAVE_SODIUM)
  return sodium_ready();
#else
  return false;
#endif
}

std::string signature_path(const std::string& model_path) {
  return model_path + ".sig";
}

Expected<PublicKey> read_public_key(const std::string& path) {
  auto line = first_line(path, "public key");
  if (!line) return line.error();
  auto h = field_after(*line, kPublicTag, path, "public key");
  if (!h) return h.error();
  PublicKey k;
  if (!unhex(*h, k.bytes, sizeof k.bytes)) {
    return Error(Errc::kInvalidArgument, "public key: '%s': expected 64 hex digits", path.c_str());
  }
  return k;
}

Expected<SecretKey> read_secret_key(const std::string& path) {
  auto line = first_line(path, "secret key");
  if (!line) return line.error();
  auto h = field_after(*line, kSecretTag, path, "secret key");
  if (!h) return h.error();
  SecretKey k;
  if (!unhex(*h, k.bytes, sizeof k.bytes)) {
    return Error(Errc::kInvalidArgument, "secret key: '%s': expected 128 hex digits", path.c_str());
  }
  return k;
}

Status generate_key_pair(const std::string& prefix) {
#if defined(APRT_HAVE_SODIUM)
  if (!sodium_ready()) return unavailable();
  PublicKey pk;
  SecretKey sk;
  crypto_sign_keypair(pk.bytes, sk.bytes);
  Status s = write_text(prefix + ".key", std::string(kSecretTag) + " " + hex(sk.bytes, 64) + "\n",
                        0600, true);
  sodium_memzero(sk.bytes, sizeof sk.bytes);
  if (!s) return s;
  return write_text(prefix + ".pub", std::string(kPublicTag) + " " + hex(pk.bytes, 32) + "\n", 0644,
                    true);
#else
  (void)prefix;
  return unavailable();
#endif
}

Status write_signature(const uint8_t* data, size_t size, const SecretKey& key,
                       const std::string& sig_path) {
#if defined(APRT_HAVE_SODIUM)
  if (!sodium_ready()) return unavailable();
  uint8_t sig[crypto_sign_BYTES];
  crypto_sign_detached(sig, nullptr, data, size, key.bytes);
  // libsodium's secret key is seed || public key: the id is the public key's first 8 bytes.
  return write_text(sig_path,
                    std::string(kSignatureTag) + " " + hex(sig, sizeof sig) + " key " +
                        hex(key.bytes + 32, 8) + "\n",
                    0644, false);
#else
  (void)data, (void)size, (void)key, (void)sig_path;
  return unavailable();
#endif
}

Status verify_signature(const uint8_t* data, size_t size, const std::string& sig_path,
                        const PublicKey& key) {
#if defined(APRT_HAVE_SODIUM)
  if (!sodium_ready()) return unavailable();
  auto line = first_line(sig_path, "signature");
  if (!line) return line.error();
  auto h = field_after(*line, kSignatureTag, sig_path, "signature");
  if (!h) return h.error();
  uint8_t sig[crypto_sign_BYTES];
  if (!unhex(*h, sig, sizeof sig)) {
    return Error(Errc::kInvalidArgument, "signature: '%s': expected 128 hex digits",
                 sig_path.c_str());
  }
  if (crypto_sign_verify_detached(sig, data, size, key.bytes) != 0) {
    const size_t at = line->find(" key ");
    const std::string signer = at == std::string::npos ? "?" : line->substr(at + 5);
    const std::string expected = hex(key.bytes, 8);
    if (signer != expected) {
      return Error(Errc::kChecksum,
                   "signature: '%s' was made with key %s, the configured public key is %s",
                   sig_path.c_str(), signer.c_str(), expected.c_str());
    }
    return Error(Errc::kChecksum,
                 "signature: '%s' does not match the model's bytes (modified after signing?)",
                 sig_path.c_str());
  }
  return ok();
#else
  (void)data, (void)size, (void)sig_path, (void)key;
  return unavailable();
#endif
}

}  // namespace aprt
