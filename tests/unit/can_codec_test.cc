// The pose on CAN: encode/decode round trip over the value range, resolution
// and saturation at the edges, E2E (CRC, alive counter, grouping), and the
// encoder checked against config/aprt_pose.dbc through the DBC reader.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <limits>
#include <random>
#include <string>

#include "drivers/can/dbc.h"
#include "drivers/output/can/pose_can_codec.h"
#include "runtime/base/allocation_counter.h"

#ifndef APRT_SOURCE_DIR
#define APRT_SOURCE_DIR "."
#endif

namespace aprt::can {
namespace {

PoseSignals sample(double x, double y, double z, double yaw) {
  PoseSignals s;
  s.state = 1;
  s.valid = true;
  s.sigma_pos_m = 1.25;
  s.sigma_yaw_deg = 2.5;
  s.x = x;
  s.y = y;
  s.z = z;
  s.qw = std::cos(yaw / 2);
  s.qz = std::sin(yaw / 2);
  s.timestamp_us = 1795000000123456ull;
  return s;
}

// Feeds a whole estimate; returns the last event.
Decoder::Event feed_all(Decoder& d, const Frame* f, int n, PoseSignals* out) {
  Decoder::Event e = Decoder::Event::kNone;
  for (int i = 0; i < n; ++i) e = d.feed(f[i], out);
  return e;
}

TEST(CanCrc, MatchesTheJ1850CheckValue) {
  // CRC-8 SAE J1850 of "123456789" is 0x4B (AUTOSAR SWS CRC Library). e2e_crc
  // prepends the data ID and skips payload[0]; with the ID as the first two
  // message bytes the same polynomial gives the same check value.
  const uint8_t msg[10] = {0, '3', '4', '5', '6', '7', '8', '9'};
  EXPECT_EQ(e2e_crc(uint16_t('1' | ('2' << 8)), msg, 8), 0x4B);
}

TEST(CanCodec, ClassicRoundTripOverTheRange) {
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> pos(-83886.0, 83886.0), zz(-327.0, 327.0),
      ang(-M_PI, M_PI);
  Ids ids;
  Decoder d(ids);
  for (int i = 0; i < 2000; ++i) {
    PoseSignals s = sample(pos(rng), pos(rng), zz(rng), ang(rng));
    Frame f[kClassicFrames];
    ASSERT_EQ(encode_classic(s, uint8_t(i & 15), ids, f), kClassicFrames);
    PoseSignals out;
    ASSERT_EQ(feed_all(d, f, kClassicFrames, &out), Decoder::Event::kEstimate) << i;
    EXPECT_NEAR(out.x, s.x, 0.005 + 1e-9);
    EXPECT_NEAR(out.y, s.y, 0.005 + 1e-9);
    EXPECT_NEAR(out.z, s.z, 0.005 + 1e-9);
    EXPECT_NEAR(out.qw, s.qw, 0.5 / 32767 + 1e-12);
    EXPECT_NEAR(out.qz, s.qz, 0.5 / 32767 + 1e-12);
    EXPECT_NEAR(out.sigma_pos_m, 1.25, 0.005);
    EXPECT_NEAR(out.sigma_yaw_deg, 2.5, 0.05);
    EXPECT_EQ(out.timestamp_us, s.timestamp_us & ((1ull << 48) - 1));
    EXPECT_TRUE(out.valid);
    EXPECT_EQ(out.flags, 0);
    EXPECT_EQ(out.state, 1);
  }
  EXPECT_EQ(d.crc_errors + d.repeated + d.skipped + d.incomplete, 0u);
}

TEST(CanCodec, FdRoundTripOverTheRange) {
  std::mt19937 rng(8);
  std::uniform_real_distribution<double> pos(-2147483.0, 2147483.0), ang(-M_PI, M_PI);
  Ids ids;
  Decoder d(ids);
  for (int i = 0; i < 2000; ++i) {
    PoseSignals s = sample(pos(rng), pos(rng), pos(rng), ang(rng));
    Frame f;
    encode_fd(s, uint8_t(i & 15), ids, &f);
    EXPECT_TRUE(f.fd);
    EXPECT_EQ(f.len, kFdLength);
    PoseSignals out;
    ASSERT_EQ(d.feed(f, &out), Decoder::Event::kEstimate);
    EXPECT_NEAR(out.x, s.x, 0.0005 + 1e-6);
    EXPECT_NEAR(out.y, s.y, 0.0005 + 1e-6);
    EXPECT_NEAR(out.z, s.z, 0.0005 + 1e-6);
    EXPECT_EQ(out.timestamp_us, s.timestamp_us);
    EXPECT_TRUE(out.valid);
  }
}

TEST(CanCodec, EdgesAreRepresentableOneStepBeyondSaturates) {
  Ids ids;
  Frame f[kClassicFrames];
  PoseSignals out;
  // The largest representable values go out valid...
  {
    Decoder d(ids);
    PoseSignals s = sample(83886.07, -83886.08, 327.67, 0);
    encode_classic(s, 0, ids, f);
    ASSERT_EQ(feed_all(d, f, kClassicFrames, &out), Decoder::Event::kEstimate);
    EXPECT_NEAR(out.x, 83886.07, 1e-6);
    EXPECT_NEAR(out.y, -83886.08, 1e-6);
    EXPECT_NEAR(out.z, 327.67, 1e-6);
    EXPECT_TRUE(out.valid);
    EXPECT_EQ(out.flags & kFlagSaturated, 0);
  }
  // ...one resolution step further saturates at the limit and is flagged.
  const double beyond[][3] = {{83886.08, 0, 0}, {0, -83886.10, 0}, {0, 0, 327.68}, {0, 0, -400}};
  for (const auto& b : beyond) {
    Decoder d(ids);
    PoseSignals s = sample(b[0], b[1], b[2], 0);
    encode_classic(s, 0, ids, f);
    ASSERT_EQ(feed_all(d, f, kClassicFrames, &out), Decoder::Event::kEstimate);
    EXPECT_FALSE(out.valid);
    EXPECT_NE(out.flags & kFlagSaturated, 0);
    if (b[0] > 0) {
      EXPECT_NEAR(out.x, 83886.07, 1e-6);
    }
    if (b[1] < 0) {
      EXPECT_NEAR(out.y, -83886.08, 1e-6);
    }
    if (b[2] > 0) {
      EXPECT_NEAR(out.z, 327.67, 1e-6);
    }
    if (b[2] < 0) {
      EXPECT_NEAR(out.z, -327.68, 1e-6);
    }
  }
  // Sigmas saturate too (a huge uncertainty must not wrap to a small one).
  {
    Decoder d(ids);
    PoseSignals s = sample(0, 0, 0, 0);
    s.sigma_pos_m = 1000;
    encode_classic(s, 0, ids, f);
    ASSERT_EQ(feed_all(d, f, kClassicFrames, &out), Decoder::Event::kEstimate);
    EXPECT_NEAR(out.sigma_pos_m, 655.35, 1e-6);
    EXPECT_FALSE(out.valid);
  }
}

TEST(CanCodec, NonFiniteNeverGoesOutValid) {
  Ids ids;
  const double nan = std::numeric_limits<double>::quiet_NaN();
  const double inf = std::numeric_limits<double>::infinity();
  for (double bad : {nan, inf, -inf}) {
    for (int field = 0; field < 4; ++field) {
      PoseSignals s = sample(10, 20, 1, 0.3);
      (field == 0 ? s.x : field == 1 ? s.y : field == 2 ? s.z : s.qw) = bad;
      Frame f[kClassicFrames], fd;
      PoseSignals out;
      Decoder d(ids);
      encode_classic(s, 3, ids, f);
      ASSERT_EQ(feed_all(d, f, kClassicFrames, &out), Decoder::Event::kEstimate);
      EXPECT_FALSE(out.valid);
      EXPECT_NE(out.flags & kFlagSaturated, 0);
      encode_fd(s, 3, ids, &fd);
      ASSERT_EQ(d.feed(fd, &out), Decoder::Event::kEstimate);
      EXPECT_FALSE(out.valid);
    }
  }
}

TEST(CanCodec, FlagsOrNotRunningClearValid) {
  Ids ids;
  Frame f[kClassicFrames];
  PoseSignals out;
  Decoder d(ids);
  PoseSignals s = sample(1, 2, 3, 0);
  s.flags = 1u << 9;  // deadline missed
  encode_classic(s, 0, ids, f);
  ASSERT_EQ(feed_all(d, f, kClassicFrames, &out), Decoder::Event::kEstimate);
  EXPECT_FALSE(out.valid);
  EXPECT_EQ(out.flags, 1u << 9);
}

TEST(CanE2E, DetectsEveryCorruptedByte) {
  Ids ids;
  Frame f[kClassicFrames];
  encode_classic(sample(100, 200, 3, 1), 5, ids, f);
  for (int frame = 0; frame < kClassicFrames; ++frame) {
    for (int byte = 0; byte < 8; ++byte) {
      for (int bit = 0; bit < 8; ++bit) {
        Decoder d(ids);
        Frame g[kClassicFrames];
        for (int i = 0; i < kClassicFrames; ++i) g[i] = f[i];
        g[frame].data[byte] ^= uint8_t(1u << bit);
        PoseSignals out;
        Decoder::Event e = Decoder::Event::kNone;
        for (int i = 0; i < kClassicFrames; ++i) {
          const Decoder::Event ei = d.feed(g[i], &out);
          if (i == frame) {
            EXPECT_EQ(ei, Decoder::Event::kCrcError);
          }
          e = ei;
        }
        EXPECT_NE(e, Decoder::Event::kEstimate);
        EXPECT_EQ(d.estimates, 0u);
      }
    }
  }
  // And for FD, a corrupted byte anywhere in the 48.
  Frame fd;
  encode_fd(sample(100, 200, 3, 1), 5, ids, &fd);
  for (int byte = 0; byte < kFdLength; ++byte) {
    Decoder d(ids);
    Frame g = fd;
    g.data[byte] ^= 0x10;
    PoseSignals out;
    EXPECT_EQ(d.feed(g, &out), Decoder::Event::kCrcError) << byte;
  }
}

TEST(CanE2E, DataIdSeparatesMessages) {
  // The same payload under another CAN id fails the CRC: frames cannot be
  // mistaken for each other even with identical content.
  Ids ids;
  Frame f[kClassicFrames];
  encode_classic(sample(1, 1, 1, 0), 0, ids, f);
  Frame moved = f[3];
  moved.id = ids.time;
  Decoder d(ids);
  PoseSignals out;
  EXPECT_EQ(d.feed(moved, &out), Decoder::Event::kCrcError);
}

TEST(CanE2E, RepeatedAndSkippedCounters) {
  Ids ids;
  Decoder d(ids);
  PoseSignals out;
  Frame f[kClassicFrames];
  encode_classic(sample(1, 2, 3, 0), 14, ids, f);
  ASSERT_EQ(feed_all(d, f, kClassicFrames, &out), Decoder::Event::kEstimate);
  // Repeated: the same estimate again is never used.
  for (int i = 0; i < kClassicFrames; ++i)
    EXPECT_EQ(d.feed(f[i], &out), Decoder::Event::kCounterRepeated);
  EXPECT_EQ(d.repeated, uint64_t(kClassicFrames));
  EXPECT_EQ(d.estimates, 1u);
  // Wrap-around 14 -> 15 -> 0 is continuous.
  encode_classic(sample(1, 2, 3, 0), 15, ids, f);
  ASSERT_EQ(feed_all(d, f, kClassicFrames, &out), Decoder::Event::kEstimate);
  encode_classic(sample(1, 2, 3, 0), 0, ids, f);
  ASSERT_EQ(feed_all(d, f, kClassicFrames, &out), Decoder::Event::kEstimate);
  EXPECT_EQ(d.skipped, 0u);
  // Skipped: 0 -> 2 is reported on the first frame, the estimate itself still decodes.
  encode_classic(sample(1, 2, 3, 0), 2, ids, f);
  EXPECT_EQ(d.feed(f[0], &out), Decoder::Event::kCounterSkipped);
  for (int i = 1; i < kClassicFrames - 1; ++i) d.feed(f[i], &out);
  EXPECT_EQ(d.feed(f[4], &out), Decoder::Event::kEstimate);
  EXPECT_EQ(d.skipped, uint64_t(kClassicFrames));
}

TEST(CanE2E, IncompleteEstimateIsNotAssembled) {
  Ids ids;
  Decoder d(ids);
  PoseSignals out;
  Frame a[kClassicFrames], b[kClassicFrames];
  encode_classic(sample(1, 2, 3, 0), 1, ids, a);
  encode_classic(sample(7, 8, 9, 0), 2, ids, b);
  // Frames 0..2 of estimate 1, then all of estimate 2: never a mix.
  for (int i = 0; i < 3; ++i) EXPECT_EQ(d.feed(a[i], &out), Decoder::Event::kNone);
  for (int i = 0; i < kClassicFrames - 1; ++i) d.feed(b[i], &out);
  ASSERT_EQ(d.feed(b[4], &out), Decoder::Event::kEstimate);
  EXPECT_NEAR(out.x, 7, 0.01);
  EXPECT_EQ(d.incomplete, 1u);
  EXPECT_EQ(d.estimates, 1u);
}

TEST(CanCodec, EncodingAllocatesNothing) {
  Ids ids;
  Frame f[kClassicFrames], fd;
  PoseSignals s = sample(1, 2, 3, 0.5);
  AllocationScope scope;
  for (int i = 0; i < 100; ++i) {
    encode_classic(s, uint8_t(i & 15), ids, f);
    encode_fd(s, uint8_t(i & 15), ids, &fd);
  }
  EXPECT_EQ(scope.count(), 0u);
}

// --- the encoder against the DBC file --------------------------------------------

const Dbc& shipped_dbc() {
  static const Dbc dbc = [] {
    auto d = load_dbc(std::string(APRT_SOURCE_DIR) + "/config/aprt_pose.dbc");
    EXPECT_TRUE(d) << d.error().message();
    return d ? d.value() : Dbc{};
  }();
  return dbc;
}

TEST(CanDbc, ShippedFileDefinesTheMessages) {
  const Dbc& dbc = shipped_dbc();
  ASSERT_EQ(dbc.messages.size(), 6u);
  Ids ids;
  const uint32_t expect[6] = {ids.status, ids.pos_xy, ids.pos_zqw, ids.quat_yz, ids.time, ids.fd};
  const int lengths[6] = {8, 8, 8, 8, 8, 48};
  for (int i = 0; i < 6; ++i) {
    const DbcMessage* m = dbc.message(expect[i]);
    ASSERT_NE(m, nullptr) << std::hex << expect[i];
    EXPECT_EQ(m->length, lengths[i]);
    ASSERT_NE(m->signal("E2E_CRC"), nullptr);
    ASSERT_NE(m->signal("E2E_Counter"), nullptr);
    EXPECT_EQ(m->signal("E2E_CRC")->start, 0);
    EXPECT_EQ(m->signal("E2E_Counter")->start, 8);
  }
  EXPECT_EQ(dbc.message(ids.status)->signal("State")->values.at(1), "RUNNING");
}

TEST(CanDbc, EncoderAgreesWithTheDbc) {
  const Dbc& dbc = shipped_dbc();
  ASSERT_FALSE(dbc.messages.empty());
  Ids ids;
  std::mt19937 rng(3);
  std::uniform_real_distribution<double> pos(-80000, 80000), ang(-M_PI, M_PI);
  for (int i = 0; i < 200; ++i) {
    PoseSignals s = sample(pos(rng), pos(rng), 12.34, ang(rng));
    s.qx = 0.01;
    s.qy = -0.02;
    Frame f[kClassicFrames], fd;
    encode_classic(s, uint8_t(i & 15), ids, f);
    encode_fd(s, uint8_t(i & 15), ids, &fd);
    auto phys = [&](const Frame& fr, const char* name) {
      const DbcMessage* m = dbc.message(fr.id);
      const DbcSignal* sg = m ? m->signal(name) : nullptr;
      EXPECT_NE(sg, nullptr) << name;
      return sg ? sg->physical(fr.data, fr.len) : NAN;
    };
    EXPECT_NEAR(phys(f[1], "PosX"), s.x, 0.005 + 1e-9);
    EXPECT_NEAR(phys(f[1], "PosY"), s.y, 0.005 + 1e-9);
    EXPECT_NEAR(phys(f[2], "PosZ"), 12.34, 0.005 + 1e-9);
    EXPECT_NEAR(phys(f[2], "QuatW"), s.qw, 1e-4);
    EXPECT_NEAR(phys(f[2], "QuatX"), 0.01, 1e-4);
    EXPECT_NEAR(phys(f[3], "QuatY"), -0.02, 1e-4);
    EXPECT_NEAR(phys(f[3], "QuatZ"), s.qz, 1e-4);
    EXPECT_EQ(phys(f[0], "Valid"), 1);
    EXPECT_EQ(phys(f[0], "State"), 1);
    EXPECT_NEAR(phys(f[0], "SigmaPos"), 1.25, 0.005);
    EXPECT_NEAR(phys(f[0], "SigmaYaw"), 2.5, 0.05);
    EXPECT_EQ(phys(f[4], "TimestampUs"), double(s.timestamp_us & ((1ull << 48) - 1)));
    for (int k = 0; k < kClassicFrames; ++k) {
      EXPECT_EQ(phys(f[k], "E2E_Counter"), i & 15);
      EXPECT_EQ(phys(f[k], "E2E_CRC"), f[k].data[0]);
    }
    EXPECT_NEAR(phys(fd, "PosX"), s.x, 0.0005 + 1e-6);
    EXPECT_NEAR(phys(fd, "PosY"), s.y, 0.0005 + 1e-6);
    EXPECT_NEAR(phys(fd, "PosZ"), 12.34, 0.0005 + 1e-6);
    EXPECT_NEAR(phys(fd, "QuatZ"), s.qz, 1e-4);
    EXPECT_EQ(phys(fd, "Valid"), 1);
  }
}

TEST(CanDbc, MalformedFilesAreRefusedWithTheLine) {
  auto d = parse_dbc("BO_ 768 X: 8 N\n SG_ A : 60|8@1+ (1,0) [0|1] \"\" N\n", "t.dbc");
  ASSERT_FALSE(d);
  EXPECT_NE(std::string(d.error().message()).find("t.dbc:2"), std::string::npos);
  auto e = parse_dbc("BO_ nonsense\n", "t.dbc");
  ASSERT_FALSE(e);
  EXPECT_NE(std::string(e.error().message()).find("t.dbc:1: malformed BO_"), std::string::npos);
  // Found by the DBC fuzzer: a huge length overflowed the signal check's
  // length in bits (signed overflow).
  auto f = parse_dbc("BO_ 1 M: 878978568 N\n SG_ S : 0|8@1+ (1,0) [0|1] \"\" N\n", "t.dbc");
  ASSERT_FALSE(f);
  EXPECT_NE(std::string(f.error().message()).find("t.dbc:1: BO_ with a length outside 0..64"),
            std::string::npos)
      << f.error().message();
}

TEST(CanDbc, MotorolaSignals) {
  // Big-endian 16-bit signal starting at bit 7 (MSB of byte 0): bytes 0x12 0x34.
  auto d = parse_dbc("BO_ 1 M: 8 N\n SG_ S : 7|16@0+ (1,0) [0|65535] \"\" N\n", "m.dbc");
  ASSERT_TRUE(d) << d.error().message();
  const uint8_t data[8] = {0x12, 0x34};
  EXPECT_EQ(d->messages[0].signals[0].raw(data, 8), 0x1234u);
}

}  // namespace
}  // namespace aprt::can

namespace aprt::can {
namespace {

// Writes encoded frames and the values that went into them, for the
// independent DBC check (tests/tools/test_dbc_independent.py, canmatrix).
// Runs as a ctest fixture with APRT_CAN_FRAMES_OUT set; skipped otherwise.
TEST(CanFrames, WriteForIndependentCheck) {
  const char* path = std::getenv("APRT_CAN_FRAMES_OUT");
  if (!path) GTEST_SKIP() << "APRT_CAN_FRAMES_OUT not set";
  FILE* f = std::fopen(path, "w");
  ASSERT_NE(f, nullptr) << path;
  std::mt19937 rng(5);
  std::uniform_real_distribution<double> pos(-80000, 80000), z(-300, 300), ang(-M_PI, M_PI);
  Ids ids;
  for (int i = 0; i < 64; ++i) {
    PoseSignals s = sample(pos(rng), pos(rng), z(rng), ang(rng));
    s.qx = 0.02 * std::sin(i);
    s.qy = -0.03 * std::cos(i);
    s.flags = (i % 9 == 0) ? uint16_t(1u << 10) : 0;
    s.state = uint8_t(i % 5);
    s.valid = s.flags == 0 && s.state == 1;
    s.timestamp_us = 1795000000000000ull + uint64_t(i) * 100000u;
    Frame c[kClassicFrames], fd;
    encode_classic(s, uint8_t(i & 15), ids, c);
    encode_fd(s, uint8_t(i & 15), ids, &fd);
    std::fprintf(f,
                 "{\"x\": %.17g, \"y\": %.17g, \"z\": %.17g, \"qw\": %.17g, \"qx\": %.17g, \"qy\": "
                 "%.17g, \"qz\": %.17g, \"state\": %u, \"flags\": %u, \"valid\": %d, \"counter\": "
                 "%d, \"t\": %llu, \"frames\": [",
                 s.x, s.y, s.z, s.qw, s.qx, s.qy, s.qz, unsigned(s.state), unsigned(s.flags),
                 s.valid ? 1 : 0, i & 15, static_cast<unsigned long long>(s.timestamp_us));
    for (int k = 0; k <= kClassicFrames; ++k) {
      const Frame& fr = k < kClassicFrames ? c[k] : fd;
      std::fprintf(f, "%s{\"id\": %u, \"data\": \"", k ? ", " : "", unsigned(fr.id));
      for (int b = 0; b < fr.len; ++b) std::fprintf(f, "%02x", fr.data[b]);
      std::fprintf(f, "\"}");
    }
    std::fprintf(f, "]}\n");
  }
  std::fclose(f);
}

}  // namespace
}  // namespace aprt::can
