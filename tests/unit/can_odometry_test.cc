// The vehicle's speed and yaw rate from its CAN bus (odometry.source: can):
// signals found by name in a DBC, decoded in the DBC's units into SI,
// paired across two messages, invalid codes and stale yaw rates refused; the
// DBC reader's bit extraction checked against an independent encoder on
// random layouts; the example DBC the project ships read as documented.
#include "drivers/input/can_odometry/can_odometry.h"

#include <gtest/gtest.h>

#include <cmath>
#include <random>
#include <string>

#include "drivers/can/dbc.h"
#include "runtime/base/allocation_counter.h"

#ifndef APRT_SOURCE_DIR
#define APRT_SOURCE_DIR "."
#endif

namespace aprt {
namespace {

using can::Frame;

// Writes `raw` into the signal's bits, bit by bit as the DBC format defines
// them (written apart from DbcSignal::raw, which it checks).
void put(const can::DbcSignal& s, uint64_t raw, uint8_t* data) {
  if (s.little_endian) {
    for (int i = 0; i < s.length; ++i) {
      const int bit = s.start + i;
      const uint8_t m = uint8_t(1u << (bit % 8));
      data[bit / 8] = ((raw >> i) & 1u) ? (data[bit / 8] | m) : (data[bit / 8] & ~m);
    }
    return;
  }
  // Motorola: the start bit is the most significant; within a byte the
  // bits go down from 7 to 0, then on to the next byte's bit 7.
  int byte = s.start / 8, bit = s.start % 8;
  for (int i = s.length - 1; i >= 0; --i) {
    const uint8_t m = uint8_t(1u << bit);
    data[byte] = ((raw >> i) & 1u) ? (data[byte] | m) : (data[byte] & ~m);
    if (bit == 0) {
      bit = 7;
      ++byte;
    } else {
      --bit;
    }
  }
}

const char* kDbc =
    "BO_ 416 Speed: 8 ESP\n"
    " SG_ VehicleSpeed : 0|16@1+ (0.01,0) [0|320] \"km/h\" ADAS\n"
    "\n"
    "BO_ 417 Yaw: 8 ESP\n"
    " SG_ YawRate : 7|16@0- (0.01,0) [-163.84|163.83] \"deg/s\" ADAS\n"
    " SG_ Mode M : 16|2@1+ (1,0) [0|3] \"\" ADAS\n"
    " SG_ Muxed m1 : 24|8@1+ (1,0) [0|255] \"deg/s\" ADAS\n"
    "\n"
    "BO_ 2566844926 Both: 8 ESP\n"
    " SG_ Speed : 0|16@1- (0.001,0) [-50|50] \"m/s\" ADAS\n"
    " SG_ Rate : 16|16@1- (0.0001,0) [-3|3] \"rad/s\" ADAS\n"
    " SG_ RateNoUnit : 32|16@1- (0.0001,0) [-3|3] \"\" ADAS\n"
    "\n"
    "BO_ 418 Gear: 2 TCU\n"
    " SG_ Direction : 0|3@1+ (1,0) [0|5] \"\" ADAS\n"
    "\n"
    "BO_ 419 Wheels: 8 ESP\n"
    " SG_ Page M : 0|4@1+ (1,0) [0|15] \"\" ADAS\n"
    " SG_ SpeedRear m2 : 8|16@1+ (0.01,0) [0|320] \"km/h\" ADAS\n"
    " SG_ GearPos m2 : 24|3@1+ (1,0) [0|5] \"\" ADAS\n"
    " SG_ Other m3 : 8|16@1+ (1,0) [0|65535] \"\" ADAS\n"
    "\n"
    "BO_ 420 Orphan: 8 ESP\n"
    " SG_ Lone m1 : 0|16@1+ (0.01,0) [0|320] \"km/h\" ADAS\n"
    "\n"
    "VAL_ 418 Direction 0 \"Park\" 1 \"Reverse\" 2 \"Neutral\" 3 \"Drive\" 7 \"Invalid\" ;\n";

can::Dbc test_dbc() {
  auto d = can::parse_dbc(kDbc, "test.dbc");
  EXPECT_TRUE(d) << d.error().message();
  return d.value();
}

CanOdometryOptions two_messages() {
  CanOdometryOptions o;
  o.speed = "Speed.VehicleSpeed";
  o.yaw_rate = "Yaw.YawRate";
  return o;
}

Frame frame_with(const can::Dbc& dbc, const char* message, const char* signal, double value) {
  const can::DbcMessage* m = dbc.message(message);
  const can::DbcSignal* s = m->signal(signal);
  Frame f;
  f.id = m->id;
  f.len = uint8_t(m->length);
  const int64_t raw = std::llround((value - s->offset) / s->factor);
  put(*s, uint64_t(raw) & (s->length == 64 ? ~0ull : ((1ull << s->length) - 1)), f.data);
  return f;
}

TEST(CanOdometry, TwoMessagesPairIntoOneSampleInSIUnits) {
  const can::Dbc dbc = test_dbc();
  auto d = CanOdometryDecoder::create(dbc, two_messages(), "test.dbc");
  ASSERT_TRUE(d) << d.error().message();
  EXPECT_EQ(d->description(), "Speed.VehicleSpeed [km/h] + Yaw.YawRate [deg/s]");
  TwistSample s;
  const int64_t t0 = 1795000000000000000;
  EXPECT_EQ(d->on_frame(frame_with(dbc, "Yaw", "YawRate", -12.5), t0, &s),
            CanOdometryDecoder::Result::kHeld);
  const AllocationScope scope;
  ASSERT_EQ(d->on_frame(frame_with(dbc, "Speed", "VehicleSpeed", 72.0), t0 + 5000000, &s),
            CanOdometryDecoder::Result::kSample);
  EXPECT_EQ(scope.count(), 0u);
  EXPECT_EQ(s.stamp_ns, t0 + 5000000);  // the speed's receive time
  EXPECT_NEAR(s.speed_mps, 20.0, 1e-9);
  EXPECT_NEAR(s.yaw_rate_radps, -12.5 * M_PI / 180.0, 1e-9);
  // Frames of other ids are not its business.
  Frame other;
  other.id = 0x555;
  other.len = 8;
  EXPECT_EQ(d->on_frame(other, t0, &s), CanOdometryDecoder::Result::kIgnored);
}

TEST(CanOdometry, ASpeedWithoutARecentYawRateIsRefused) {
  const can::Dbc dbc = test_dbc();
  CanOdometryOptions o = two_messages();
  o.max_pair_age_ms = 50;
  auto d = CanOdometryDecoder::create(dbc, o, "test.dbc");
  ASSERT_TRUE(d) << d.error().message();
  TwistSample s;
  const int64_t t0 = 1795000000000000000;
  EXPECT_EQ(d->on_frame(frame_with(dbc, "Speed", "VehicleSpeed", 50.0), t0, &s),
            CanOdometryDecoder::Result::kRefused);
  EXPECT_STREQ(d->last_refusal(), "no yaw rate within max_pair_age_ms of the speed");
  d->on_frame(frame_with(dbc, "Yaw", "YawRate", 1.0), t0, &s);
  EXPECT_EQ(d->on_frame(frame_with(dbc, "Speed", "VehicleSpeed", 50.0), t0 + 50000000, &s),
            CanOdometryDecoder::Result::kSample);
  EXPECT_EQ(d->on_frame(frame_with(dbc, "Speed", "VehicleSpeed", 50.0), t0 + 51000000, &s),
            CanOdometryDecoder::Result::kRefused);
}

TEST(CanOdometry, InvalidCodesShortFramesAndAbsurdValuesAreRefused) {
  const can::Dbc dbc = test_dbc();
  auto d = CanOdometryDecoder::create(dbc, two_messages(), "test.dbc");
  ASSERT_TRUE(d) << d.error().message();
  TwistSample s;
  const int64_t t0 = 1795000000000000000;
  // 0x7FFF: 327.67 deg/s, outside the DBC's range: the ECU's "invalid".
  Frame yaw;
  yaw.id = 417;
  yaw.len = 8;
  yaw.data[0] = 0x7F;
  yaw.data[1] = 0xFF;
  EXPECT_EQ(d->on_frame(yaw, t0, &s), CanOdometryDecoder::Result::kRefused);
  EXPECT_STREQ(d->last_refusal(), "value outside the DBC's range (an invalid code?)");
  // ... and a refused yaw rate is not kept: the next speed has none to pair with.
  EXPECT_EQ(d->on_frame(frame_with(dbc, "Speed", "VehicleSpeed", 10.0), t0, &s),
            CanOdometryDecoder::Result::kRefused);
  d->on_frame(frame_with(dbc, "Yaw", "YawRate", 0.0), t0, &s);
  Frame speed = frame_with(dbc, "Speed", "VehicleSpeed", 10.0);
  speed.data[0] = speed.data[1] = 0xFF;  // 655.35 km/h
  EXPECT_EQ(d->on_frame(speed, t0, &s), CanOdometryDecoder::Result::kRefused);
  speed = frame_with(dbc, "Speed", "VehicleSpeed", 10.0);
  speed.len = 1;  // the signal needs two bytes
  EXPECT_EQ(d->on_frame(speed, t0, &s), CanOdometryDecoder::Result::kRefused);
  EXPECT_STREQ(d->last_refusal(), "frame shorter than its signal");
}

TEST(CanOdometry, OneMessageCarryingBothGivesASamplePerFrame) {
  const can::Dbc dbc = test_dbc();
  CanOdometryOptions o;
  o.speed = "Both.Speed";
  o.yaw_rate = "Both.Rate";
  o.yaw_rate_clockwise = true;
  auto d = CanOdometryDecoder::create(dbc, o, "test.dbc");
  ASSERT_TRUE(d) << d.error().message();
  EXPECT_EQ(d->speed_id(), d->yaw_rate_id());
  EXPECT_EQ(d->speed_id(), 0x18FEF1FEu);  // the DBC's bit 31 (extended) masked off
  const can::DbcMessage* m = dbc.message("Both");
  Frame f;
  f.id = m->id;
  f.len = 8;
  put(*m->signal("Speed"), uint64_t(int64_t(-2500)) & 0xFFFF, f.data);  // reversing at 2.5 m/s
  put(*m->signal("Rate"), 1500, f.data);
  TwistSample s;
  ASSERT_EQ(d->on_frame(f, 1795000000000000000, &s), CanOdometryDecoder::Result::kSample);
  EXPECT_NEAR(s.speed_mps, -2.5, 1e-9);
  EXPECT_NEAR(s.yaw_rate_radps, -0.15, 1e-9);  // clockwise positive on the bus
}

TEST(CanOdometry, ConfigurationErrorsSayWhatTheDbcHas) {
  const can::Dbc dbc = test_dbc();
  // The error's message ("" when the signals were found).
  const auto error_of = [&](const CanOdometryOptions& o) -> std::string {
    auto d = CanOdometryDecoder::create(dbc, o, "test.dbc");
    return d ? std::string() : std::string(d.error().message());
  };
  const auto has = [](const std::string& message, const char* part) {
    return message.find(part) != std::string::npos;
  };
  CanOdometryOptions o = two_messages();
  o.speed = "Sped.VehicleSpeed";
  std::string e = error_of(o);
  EXPECT_TRUE(has(e, "test.dbc has no message 'Sped'")) << e;
  EXPECT_TRUE(has(e, "it has Speed, Yaw, Both")) << e;
  o = two_messages();
  o.yaw_rate = "Yaw.Rate";
  e = error_of(o);
  EXPECT_TRUE(has(e, "no signal 'Rate'")) << e;
  EXPECT_TRUE(has(e, "it has YawRate, Mode, Muxed")) << e;
  o.yaw_rate = "YawRate";
  e = error_of(o);
  EXPECT_TRUE(has(e, "is not MESSAGE.SIGNAL")) << e;
  o.yaw_rate = "Yaw.Muxed";  // multiplexed: read from the frames of its page
  EXPECT_EQ(error_of(o), "");
  o.yaw_rate = "Orphan.Lone";
  o.yaw_rate_unit = "deg/s";
  e = error_of(o);
  EXPECT_TRUE(has(e, "is multiplexed (m1) but message Orphan in test.dbc has no multiplexor")) << e;
  o.yaw_rate_unit = "";
  // A signal without a unit (or one of the other quantity) needs the unit said.
  o.yaw_rate = "Both.RateNoUnit";
  e = error_of(o);
  EXPECT_TRUE(has(e, "set odometry.can.yaw_rate_unit")) << e;
  o.yaw_rate_unit = "rad/s";
  EXPECT_EQ(error_of(o), "");
  o = two_messages();
  o.speed = "Yaw.YawRate";  // deg/s is no speed
  e = error_of(o);
  EXPECT_TRUE(has(e, "not a speed aprt knows")) << e;
}

// Most wheel-speed signals have no sign: the direction of travel (a gear or
// direction signal) gives it, paired like the yaw rate; a direction that is
// stale, missing or an invalid code refuses the speed rather than guess.
TEST(CanOdometry, AnUnsignedSpeedTakesTheDirectionsSign) {
  const can::Dbc dbc = test_dbc();
  CanOdometryOptions o = two_messages();
  o.direction = "Gear.Direction";
  o.reverse_values = {1};
  auto d = CanOdometryDecoder::create(dbc, o, "test.dbc");
  ASSERT_TRUE(d) << d.error().message();
  EXPECT_EQ(d->description(),
            "Speed.VehicleSpeed [km/h] + Yaw.YawRate [deg/s], direction Gear.Direction "
            "(reverse: 1)");
  uint32_t ids[3];
  ASSERT_EQ(d->ids(ids), 3);
  EXPECT_EQ(ids[2], 418u);
  TwistSample s;
  const int64_t t0 = 1795000000000000000, ms = 1000000;
  const Frame speed = frame_with(dbc, "Speed", "VehicleSpeed", 7.2);
  d->on_frame(frame_with(dbc, "Yaw", "YawRate", 0.0), t0, &s);
  EXPECT_EQ(d->on_frame(speed, t0, &s), CanOdometryDecoder::Result::kRefused);
  EXPECT_STREQ(d->last_refusal(), "no direction within max_pair_age_ms of the speed");
  EXPECT_EQ(d->on_frame(frame_with(dbc, "Gear", "Direction", 1), t0, &s),
            CanOdometryDecoder::Result::kHeld);
  {
    const AllocationScope scope;
    ASSERT_EQ(d->on_frame(speed, t0 + 10 * ms, &s), CanOdometryDecoder::Result::kSample);
    EXPECT_EQ(scope.count(), 0u);
  }
  EXPECT_NEAR(s.speed_mps, -2.0, 1e-9);  // reversing
  d->on_frame(frame_with(dbc, "Gear", "Direction", 3), t0 + 20 * ms, &s);
  d->on_frame(frame_with(dbc, "Yaw", "YawRate", 0.0), t0 + 20 * ms, &s);
  ASSERT_EQ(d->on_frame(speed, t0 + 30 * ms, &s), CanOdometryDecoder::Result::kSample);
  EXPECT_NEAR(s.speed_mps, 2.0, 1e-9);  // "Drive"
  // A stale direction pairs with nothing.
  d->on_frame(frame_with(dbc, "Yaw", "YawRate", 0.0), t0 + 200 * ms, &s);
  EXPECT_EQ(d->on_frame(speed, t0 + 200 * ms, &s), CanOdometryDecoder::Result::kRefused);
  // 7, outside the DBC's range [0|5], is the ECU's "Invalid": refused, and
  // the direction before it is not kept.
  d->on_frame(frame_with(dbc, "Gear", "Direction", 3), t0 + 210 * ms, &s);
  EXPECT_EQ(d->on_frame(frame_with(dbc, "Gear", "Direction", 7), t0 + 215 * ms, &s),
            CanOdometryDecoder::Result::kRefused);
  EXPECT_EQ(d->on_frame(speed, t0 + 220 * ms, &s), CanOdometryDecoder::Result::kRefused);
  EXPECT_STREQ(d->last_refusal(), "no direction within max_pair_age_ms of the speed");
  // Without reverse_values the error says what the DBC calls each value.
  o.reverse_values.clear();
  auto e = CanOdometryDecoder::create(dbc, o, "test.dbc");
  ASSERT_FALSE(e);
  EXPECT_NE(std::string(e.error().message())
                .find("needs odometry.can.reverse_values (its raw values that mean reversing); "
                      "the DBC names 0 'Park', 1 'Reverse', 2 'Neutral', 3 'Drive', 7 'Invalid'"),
            std::string::npos)
      << e.error().message();
}

// A multiplexed signal is in the frames whose multiplexor has its value: a
// frame of another page is passed over, not refused.
TEST(CanOdometry, AMultiplexedSignalIsReadFromItsPage) {
  const can::Dbc dbc = test_dbc();
  CanOdometryOptions o = two_messages();
  o.speed = "Wheels.SpeedRear";
  o.direction = "Wheels.GearPos";  // on the same page of the same message
  o.reverse_values = {1};
  auto d = CanOdometryDecoder::create(dbc, o, "test.dbc");
  ASSERT_TRUE(d) << d.error().message();
  uint32_t ids[3];
  ASSERT_EQ(d->ids(ids), 2);
  const can::DbcMessage* m = dbc.message("Wheels");
  Frame page2 = frame_with(dbc, "Wheels", "SpeedRear", 36.0);
  put(*m->signal("Page"), 2, page2.data);
  put(*m->signal("GearPos"), 1, page2.data);
  Frame page3 = frame_with(dbc, "Wheels", "Other", 65000);
  put(*m->signal("Page"), 3, page3.data);
  TwistSample s;
  const int64_t t0 = 1795000000000000000;
  d->on_frame(frame_with(dbc, "Yaw", "YawRate", 5.0), t0, &s);
  EXPECT_EQ(d->on_frame(page3, t0, &s), CanOdometryDecoder::Result::kIgnored);
  ASSERT_EQ(d->on_frame(page2, t0, &s), CanOdometryDecoder::Result::kSample);
  EXPECT_NEAR(s.speed_mps, -10.0, 1e-9);
  EXPECT_NEAR(s.yaw_rate_radps, 5.0 * M_PI / 180.0, 1e-9);
}

TEST(CanOdometry, UnitsAreConverted) {
  EXPECT_DOUBLE_EQ(speed_unit_scale("km/h"), 1.0 / 3.6);
  EXPECT_DOUBLE_EQ(speed_unit_scale("m/s"), 1.0);
  EXPECT_DOUBLE_EQ(speed_unit_scale("mph"), 0.44704);
  EXPECT_EQ(speed_unit_scale("deg/s"), 0.0);
  EXPECT_DOUBLE_EQ(yaw_rate_unit_scale("deg/s"), M_PI / 180.0);
  EXPECT_DOUBLE_EQ(yaw_rate_unit_scale("\xC2\xB0/s"), M_PI / 180.0);
  EXPECT_DOUBLE_EQ(yaw_rate_unit_scale("rad/s"), 1.0);
  EXPECT_EQ(yaw_rate_unit_scale("km/h"), 0.0);
}

// DbcSignal::raw/physical against the independent encoder: random layouts
// (either byte order, signed or not, 1..32 bits anywhere in 8 or 64 bytes)
// and random values.
TEST(CanOdometry, DbcBitExtractionMatchesAnIndependentEncoderOnRandomLayouts) {
  std::mt19937 rng(31);
  for (int trial = 0; trial < 4000; ++trial) {
    can::DbcSignal s;
    const int bytes = (trial % 3 == 0) ? 64 : 8;
    s.length = 1 + int(rng() % 32);
    s.little_endian = rng() % 2;
    s.is_signed = rng() % 2 && s.length > 1;
    if (s.little_endian) {
      s.start = int(rng() % uint32_t(bytes * 8 - s.length + 1));
    } else {
      // Motorola: the MSB anywhere the signal still fits before the end.
      for (;;) {
        s.start = int(rng() % uint32_t(bytes * 8));
        const int msb_byte = s.start / 8, bits_in_first = s.start % 8 + 1;
        const int rest = s.length - bits_in_first;
        const int last_byte = rest <= 0 ? msb_byte : msb_byte + (rest + 7) / 8;
        if (last_byte < bytes) break;
      }
    }
    uint8_t data[64];
    for (auto& b : data) b = uint8_t(rng());
    const uint64_t mask = (1ull << s.length) - 1;
    const uint64_t raw = (uint64_t(rng()) << 32 | rng()) & mask;
    put(s, raw, data);
    ASSERT_EQ(s.raw(data, size_t(bytes)), raw) << "start " << s.start << " length " << s.length
                                               << (s.little_endian ? " intel" : " motorola");
    s.factor = 0.5;
    s.offset = -3;
    const double want =
        (s.is_signed ? double(int64_t(raw << (64 - s.length)) >> (64 - s.length)) : double(raw)) *
            0.5 -
        3;
    ASSERT_EQ(s.physical(data, size_t(bytes)), want);
  }
}

TEST(CanOdometry, MultiplexedSignalsParseAndMalformedIndicatorsAreRefused) {
  const can::Dbc dbc = test_dbc();
  const can::DbcMessage* m = dbc.message("Yaw");
  ASSERT_NE(m, nullptr);
  EXPECT_TRUE(m->signal("Mode")->multiplexor);
  EXPECT_EQ(m->signal("Muxed")->mux_value, 1);
  EXPECT_EQ(m->signal("YawRate")->mux_value, -1);
  // A Motorola signal running past its message is refused as an Intel one is.
  auto past = can::parse_dbc("BO_ 1 A: 1 X\n SG_ S : 7|16@0+ (1,0) [0|1] \"\" X\n", "past.dbc");
  ASSERT_FALSE(past);
  EXPECT_NE(std::string(past.error().message()).find("past.dbc:2: SG_ extends past"),
            std::string::npos)
      << past.error().message();
  auto bad = can::parse_dbc("BO_ 1 A: 8 X\n SG_ S mx : 0|8@1+ (1,0) [0|1] \"\" X\n", "bad.dbc");
  ASSERT_FALSE(bad);
  EXPECT_NE(std::string(bad.error().message()).find("bad.dbc:2: SG_ with a malformed multiplexer"),
            std::string::npos)
      << bad.error().message();
}

// The DBC shipped as the example reads as docs/configuration.md shows it.
TEST(CanOdometry, TheExampleDbcGivesTheDocumentedSignals) {
  auto dbc = can::load_dbc(APRT_SOURCE_DIR "/config/vehicle_odometry_example.dbc");
  ASSERT_TRUE(dbc) << dbc.error().message();
  CanOdometryOptions o;
  o.speed = "ESP_WheelSpeed.VehicleSpeed";
  o.yaw_rate = "ESP_YawRate.YawRate";
  auto d = CanOdometryDecoder::create(dbc.value(), o, "example");
  ASSERT_TRUE(d) << d.error().message();
  // As in the docs: `cansend can0 1A0#20 1C ...` is 72.00 km/h; 1A1#04 E2 is 12.50 deg/s.
  Frame speed, yaw;
  speed.id = 0x1A0;
  yaw.id = 0x1A1;
  speed.len = yaw.len = 8;
  speed.data[0] = 0x20;
  speed.data[1] = 0x1C;
  yaw.data[0] = 0x04;
  yaw.data[1] = 0xE2;
  TwistSample s;
  EXPECT_EQ(d->on_frame(yaw, 1795000000000000000, &s), CanOdometryDecoder::Result::kHeld);
  ASSERT_EQ(d->on_frame(speed, 1795000000010000000, &s), CanOdometryDecoder::Result::kSample);
  EXPECT_NEAR(s.speed_mps, 20.0, 1e-9);
  EXPECT_NEAR(s.yaw_rate_radps, 12.5 * M_PI / 180.0, 1e-9);
  // With its gear as the direction: `cansend can0 1A2#01` is R.
  o.direction = "TCU_Gear.GearPosition";
  o.reverse_values = {1};
  auto g = CanOdometryDecoder::create(dbc.value(), o, "example");
  ASSERT_TRUE(g) << g.error().message();
  Frame gear;
  gear.id = 0x1A2;
  gear.len = 2;
  gear.data[0] = 0x01;
  EXPECT_EQ(g->on_frame(yaw, 1795000000000000000, &s), CanOdometryDecoder::Result::kHeld);
  EXPECT_EQ(g->on_frame(gear, 1795000000000000000, &s), CanOdometryDecoder::Result::kHeld);
  ASSERT_EQ(g->on_frame(speed, 1795000000010000000, &s), CanOdometryDecoder::Result::kSample);
  EXPECT_NEAR(s.speed_mps, -20.0, 1e-9);
}

}  // namespace
}  // namespace aprt
