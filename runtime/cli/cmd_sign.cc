// aprt sign keygen PREFIX                      -> PREFIX.key (0600), PREFIX.pub
// aprt sign MODEL --key PREFIX.key             -> MODEL.sig
// aprt sign --verify MODEL --public-key PREFIX.pub
//
// Ed25519 signatures for model_signing (runtime/loop/model_signature.h). The
// secret key stays with whoever releases models; the ECU gets the .pub file.
#include <cstdio>
#include <cstring>
#include <string>

#include "runtime/cli/args.h"
#include "runtime/cli/commands.h"
#include "runtime/engine/engine.h"
#include "runtime/loop/model_signature.h"

namespace aprt::cli {

int cmd_sign(int argc, char** argv) {
  Args args(argc, argv);
  if (args.flag("--help")) {
    std::printf(
        "usage: aprt sign keygen PREFIX          make PREFIX.key (secret, mode 0600) and\n"
        "                                        PREFIX.pub (for model_signing.public_key)\n"
        "       aprt sign MODEL --key KEY        write MODEL.sig\n"
        "       aprt sign --verify MODEL --public-key PUB\n");
    return 0;
  }
  const bool verify = args.flag("--verify");
  const char* key_path = args.value("--key");
  const char* pub_path = args.value("--public-key");
  const char* first = args.positional();
  const char* second = first && !std::strcmp(first, "keygen") ? args.positional() : nullptr;
  if (args.refuse("sign")) return 2;
  if (!first) {
    std::fprintf(stderr,
                 "aprt sign: usage: aprt sign keygen PREFIX | MODEL --key KEY | "
                 "--verify MODEL --public-key PUB\n");
    return 2;
  }
  if (!model_signing_available()) {
    std::fprintf(stderr,
                 "aprt sign: this build has no libsodium (install libsodium-dev, rebuild)\n");
    return 1;
  }
  if (!std::strcmp(first, "keygen")) {
    if (!second) {
      std::fprintf(stderr, "aprt sign keygen: give the key files' PREFIX\n");
      return 2;
    }
    if (Status s = generate_key_pair(second); !s) {
      std::fprintf(stderr, "aprt sign: %s\n", s.error().message());
      return 1;
    }
    std::printf("aprt sign: wrote %s.key (secret: keep it off the vehicle) and %s.pub\n", second,
                second);
    return 0;
  }
  auto bytes = Engine::read_model_file(first);
  if (!bytes) {
    std::fprintf(stderr, "aprt sign: %s\n", bytes.error().message());
    return 2;
  }
  const std::string sig = signature_path(first);
  if (verify) {
    if (!pub_path) {
      std::fprintf(stderr, "aprt sign --verify: give --public-key PUB\n");
      return 2;
    }
    auto key = read_public_key(pub_path);
    if (!key) {
      std::fprintf(stderr, "aprt sign: %s\n", key.error().message());
      return 2;
    }
    if (Status s = verify_signature(bytes->data(), bytes->size(), sig, *key); !s) {
      std::fprintf(stderr, "aprt sign: %s: %s\n", first, s.error().message());
      return 1;
    }
    std::printf("aprt sign: %s: signature valid (%s)\n", first, sig.c_str());
    return 0;
  }
  if (!key_path) {
    std::fprintf(stderr, "aprt sign: give --key KEY (made by aprt sign keygen)\n");
    return 2;
  }
  // A model that does not load is not worth signing: check it first.
  auto engine = Engine::load_memory(bytes->data(), bytes->size());
  if (!engine) {
    std::fprintf(stderr, "aprt sign: %s: %s\n", first, engine.error().message());
    return 2;
  }
  auto key = read_secret_key(key_path);
  if (!key) {
    std::fprintf(stderr, "aprt sign: %s\n", key.error().message());
    return 2;
  }
  if (Status s = write_signature(bytes->data(), bytes->size(), *key, sig); !s) {
    std::fprintf(stderr, "aprt sign: %s\n", s.error().message());
    return 1;
  }
  std::printf("aprt sign: wrote %s\n", sig.c_str());
  return 0;
}

}  // namespace aprt::cli
