// candump log lines: both formats candump writes, and the lines that are
// neither (each once read as a frame guessed from part of it).
#include "drivers/output/can/candump_log.h"

#include <gtest/gtest.h>

#include <cstring>
#include <string>
#include <string_view>

namespace aprt::can {
namespace {

// Parses a line that must be a frame.
bool frame(std::string_view line, Frame* f, double* t) {
  auto r = parse_candump_line(line, f, t);
  EXPECT_TRUE(r) << line << ": " << r.error().message();
  return r && r.value() == LogLine::kFrame;
}

TEST(CandumpLog, ReadsBothFormats) {
  Frame f;
  double t = 0;
  ASSERT_TRUE(frame("(1700000000.123456) can0 301#00112233", &f, &t));
  EXPECT_EQ(f.id, 0x301u);
  EXPECT_EQ(f.len, 4);
  EXPECT_EQ(f.data[3], 0x33);
  EXPECT_DOUBLE_EQ(t, 1700000000.123456);
  ASSERT_TRUE(frame("(0.5) vcan0 310##1" + std::string(24, 'a'), &f, &t));
  EXPECT_TRUE(f.fd);
  EXPECT_EQ(f.len, 12);
  ASSERT_TRUE(frame("  can0  301   [8]  00 11 22 33 44 55 66 77", &f, &t));
  EXPECT_EQ(f.len, 8);
  EXPECT_EQ(f.data[7], 0x77);
  ASSERT_TRUE(frame(" (12.000001)  can0  1ABCDEF0  [2]  01 02", &f, &t));  // candump -ta
  EXPECT_EQ(f.id, 0x1ABCDEF0u);
  ASSERT_TRUE(frame("(1.0) can0 20000004#0000000000000000", &f, &t));  // an error frame
  EXPECT_EQ(f.id, 0x20000004u);
  ASSERT_TRUE(frame("(1.0) can0 123#R", &f, &t));
  EXPECT_EQ(f.len, 0);
  for (const char* blank : {"", "   ", "# a comment"}) {
    auto r = parse_candump_line(blank, &f, &t);
    ASSERT_TRUE(r);
    EXPECT_EQ(r.value(), LogLine::kBlank);
  }
}

TEST(CandumpLog, LinesThatAreNoFrameAreRefusedWithTheReason) {
  const struct {
    const char* line;
    const char* reason;
  } cases[] = {
      {"(1.0) can0 3012#00", "id '3012' is not 3 or 8 hex digits"},
      {"(1.0) can0 8FF#00", "standard id 0x8FF above 0x7FF"},
      {"(1.0) can0 301#001", "odd number of hex digits"},
      {"(1.0) can0 301#00112233445566778899", "10 data bytes (at most 8 in classic CAN)"},
      {"(1.0) can0 310##1"
       "00112233445566778899",
       "10 data bytes (CAN FD has"},
      {"(1.0) can0 301#zz", "data 'zz' is not hex"},
      {"(1.0) can0 301#00 extra", "trailing text"},
      {"(nan) can0 301#00", "'nan' is not a time in seconds"},
      {"(-1) can0 301#00", "is not a time in seconds"},
      {"  can0  301   [4]  00 11", "2 bytes where [4] says 4"},
      {"  can0  301   [8]  00 11 22 33 44 55 66 77 88", "more bytes than [8]"},
      {"  can0  301   [9]  00", "length 9 is no CAN frame's"},
      {"  can0  301   eight  00", "'eight' is not a [length]"},
      {"random words here", "id 'words' is not 3 or 8 hex digits"},
  };
  for (const auto& c : cases) {
    Frame f;
    double t = 0;
    auto r = parse_candump_line(c.line, &f, &t);
    ASSERT_FALSE(r) << "accepted: " << c.line;
    EXPECT_NE(std::strstr(r.error().message(), c.reason), nullptr)
        << c.line << " -> " << r.error().message();
  }
  Frame f;
  double t = 0;
  EXPECT_FALSE(parse_candump_line(std::string_view("(1.0) can0 301#00\0", 18), &f, &t));
}

}  // namespace
}  // namespace aprt::can
