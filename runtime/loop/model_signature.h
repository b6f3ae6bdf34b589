// Ed25519 signatures over model files (libsodium), so an ECU runs only models
// its integrator signed. A detached signature beside the model,
// MODEL.aprt.sig, covers every byte of the file; keys and signatures are
// one-line text files:
//
//   KEY.pub          aprt-ed25519-public-key <64 hex digits>
//   KEY.key (0600)   aprt-ed25519-secret-key <128 hex digits>
//   MODEL.aprt.sig   aprt-ed25519-signature <128 hex digits> key <16 hex digits>
//
// The key id in the signature (the public key's first 8 bytes) only makes
// the message useful when the wrong key signed; verification uses the key.
// `aprt sign` makes keys and signatures. Off the real-time path: used at
// start and on a model reload.
#pragma once

#include <cstddef>
#include <cstdint>
#include <string>

#include "runtime/base/expected.h"

namespace aprt {

struct PublicKey {
  uint8_t bytes[32];
};
struct SecretKey {
  uint8_t bytes[64];
};

// False when this build has no libsodium: every function below then fails with a message.
bool model_signing_available();

std::string signature_path(const std::string& model_path);
Expected<PublicKey> read_public_key(const std::string& path);
Expected<SecretKey> read_secret_key(const std::string& path);
// Writes PREFIX.pub and PREFIX.key (mode 0600); refuses to overwrite either.
Status generate_key_pair(const std::string& prefix);
Status write_signature(const uint8_t* data, size_t size, const SecretKey& key,
                       const std::string& sig_path);
// ok() when sig_path holds a valid signature of the bytes by `key`; else why not.
Status verify_signature(const uint8_t* data, size_t size, const std::string& sig_path,
                        const PublicKey& key);

}  // namespace aprt
