#include "runtime/loop/model_signature.h"

#include <gtest/gtest.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cstdio>
#include <string>
#include <vector>

namespace aprt {
namespace {

class ModelSignature : public ::testing::Test {
 protected:
  void SetUp() override {
    if (!model_signing_available()) GTEST_SKIP() << "built without libsodium";
    char d[] = "/tmp/aprt_sig_XXXXXX";
    ASSERT_NE(mkdtemp(d), nullptr);
    dir_ = d;
    for (int i = 0; i < 10000; ++i) bytes_.push_back(uint8_t(i * 31 + 7));
  }
  void TearDown() override {
    if (!dir_.empty()) std::system(("rm -rf " + dir_).c_str());  // NOLINT(cert-env33-c)
  }
  std::string path(const char* name) const { return dir_ + "/" + name; }
  void write(const char* name, const std::string& text) const {
    FILE* f = std::fopen(path(name).c_str(), "w");
    std::fputs(text.c_str(), f);
    std::fclose(f);
  }
  std::string dir_;
  std::vector<uint8_t> bytes_;
};

TEST_F(ModelSignature, SignVerifyAndEveryWayToFail) {
  ASSERT_TRUE(generate_key_pair(path("k")));
  struct stat st {};
  ASSERT_EQ(stat(path("k.key").c_str(), &st), 0);
  EXPECT_EQ(st.st_mode & 0777, 0600u);         // the secret key is private
  EXPECT_FALSE(generate_key_pair(path("k")));  // never overwritten
  auto sk = read_secret_key(path("k.key"));
  auto pk = read_public_key(path("k.pub"));
  ASSERT_TRUE(sk && pk);
  const std::string sig = path("m.aprt.sig");
  ASSERT_TRUE(write_signature(bytes_.data(), bytes_.size(), *sk, sig));
  EXPECT_TRUE(verify_signature(bytes_.data(), bytes_.size(), sig, *pk));

  // One flipped bit anywhere.
  std::vector<uint8_t> tampered = bytes_;
  tampered[5000] ^= 0x10;
  auto s = verify_signature(tampered.data(), tampered.size(), sig, *pk);
  ASSERT_FALSE(s);
  EXPECT_NE(std::string(s.error().message()).find("does not match the model's bytes"),
            std::string::npos);
  // Truncated.
  EXPECT_FALSE(verify_signature(bytes_.data(), bytes_.size() - 1, sig, *pk));
  // Another key.
  ASSERT_TRUE(generate_key_pair(path("other")));
  auto other = read_public_key(path("other.pub"));
  s = verify_signature(bytes_.data(), bytes_.size(), sig, *other);
  ASSERT_FALSE(s);
  EXPECT_NE(std::string(s.error().message()).find("was made with key"), std::string::npos);
  // Missing and malformed files.
  s = verify_signature(bytes_.data(), bytes_.size(), path("none.sig"), *pk);
  ASSERT_FALSE(s);
  EXPECT_NE(std::string(s.error().message()).find("cannot open"), std::string::npos);
  write("bad.sig", "aprt-ed25519-signature 12zz key 00\n");
  s = verify_signature(bytes_.data(), bytes_.size(), path("bad.sig"), *pk);
  ASSERT_FALSE(s);
  EXPECT_NE(std::string(s.error().message()).find("expected 128 hex digits"), std::string::npos);
  write("wrong.pub", "ssh-ed25519 AAAA\n");
  auto w = read_public_key(path("wrong.pub"));
  ASSERT_FALSE(w);
  EXPECT_NE(std::string(w.error().message()).find("not an aprt public key file"),
            std::string::npos);
  write("empty.pub", "");
  EXPECT_FALSE(read_public_key(path("empty.pub")));
}

}  // namespace
}  // namespace aprt
