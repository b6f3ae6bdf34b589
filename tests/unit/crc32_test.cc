// CRC-32: the check value of the standard, and the implementation this CPU
// runs against the table reference on random data of odd lengths, offsets
// and continuations.
#include "runtime/base/crc32.h"

#include <gtest/gtest.h>

#include <cstring>
#include <random>
#include <vector>

namespace aprt {
namespace {

TEST(Crc32, CheckValue) {
  const char* s = "123456789";
  EXPECT_EQ(crc32(s, 9), 0xCBF43926u);
  EXPECT_EQ(crc32__table(s, 9), 0xCBF43926u);
  EXPECT_EQ(crc32(s, 0), 0u);
}

TEST(Crc32, MatchesTheTableOnRandomData) {
  SCOPED_TRACE(crc32_implementation());
  std::mt19937 rng(7);
  std::vector<unsigned char> buf(70000);
  for (auto& b : buf) b = static_cast<unsigned char>(rng());
  std::uniform_int_distribution<size_t> offset(0, 63), len(0, 4200);
  for (int trial = 0; trial < 3000; ++trial) {
    const size_t at = offset(rng);
    const size_t n = trial < 200 ? size_t(trial) : len(rng);
    const uint32_t seed = trial % 3 ? uint32_t(rng()) : 0u;
    ASSERT_EQ(crc32(buf.data() + at, n, seed), crc32__table(buf.data() + at, n, seed))
        << "offset " << at << " length " << n;
  }
  EXPECT_EQ(crc32(buf.data(), buf.size()), crc32__table(buf.data(), buf.size()));
}

TEST(Crc32, ContinuesAcrossPieces) {
  std::vector<unsigned char> buf(10007);
  for (size_t i = 0; i < buf.size(); ++i) buf[i] = static_cast<unsigned char>(i * 131 + 7);
  const uint32_t whole = crc32(buf.data(), buf.size());
  for (size_t cut : {size_t(1), size_t(63), size_t(64), size_t(4096), size_t(9999)}) {
    EXPECT_EQ(crc32(buf.data() + cut, buf.size() - cut, crc32(buf.data(), cut)), whole) << cut;
  }
}

}  // namespace
}  // namespace aprt
