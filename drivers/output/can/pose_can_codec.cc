#include "drivers/output/can/pose_can_codec.h"

#include <cmath>
#include <cstring>

namespace aprt::can {
namespace {

constexpr double kQuatScale = 1.0 / 32767.0;

struct Packed {
  int64_t raw;
  bool saturated;
};

// Physical value -> raw signed integer of `bits`, rounded, saturated.
Packed pack_signed(double v, double scale, int bits) {
  const int64_t lo = -(int64_t(1) << (bits - 1)), hi = (int64_t(1) << (bits - 1)) - 1;
  if (!std::isfinite(v)) return {0, true};
  const double r = std::nearbyint(v / scale);
  if (r < double(lo)) return {lo, true};
  if (r > double(hi)) return {hi, true};
  return {int64_t(r), false};
}

Packed pack_unsigned(double v, double scale, int bits) {
  const uint64_t hi = bits >= 64 ? ~uint64_t(0) : (uint64_t(1) << bits) - 1;
  if (!std::isfinite(v)) return {int64_t(hi), true};
  const double r = std::nearbyint(v / scale);
  if (r < 0) return {0, true};
  if (r > double(hi)) return {int64_t(hi), true};
  return {int64_t(r), false};
}

int64_t sign_extend(uint64_t v, int bits) {
  const uint64_t m = uint64_t(1) << (bits - 1);
  return int64_t((v ^ m) - m);
}

void seal(Frame* f, uint8_t counter) {
  f->data[1] = uint8_t((f->data[1] & 0xF0) | (counter & 0x0F));
  f->data[0] = e2e_crc(uint16_t(f->id), f->data, f->len);
}

}  // namespace

void put_bits(uint8_t* data, int start, int length, uint64_t value) {
  for (int i = 0; i < length; ++i) {
    const int bit = start + i;
    const uint8_t mask = uint8_t(1u << (bit % 8));
    if ((value >> i) & 1u) {
      data[bit / 8] |= mask;
    } else {
      data[bit / 8] &= uint8_t(~mask);
    }
  }
}

uint64_t get_bits(const uint8_t* data, int start, int length) {
  uint64_t v = 0;
  for (int i = 0; i < length; ++i) {
    const int bit = start + i;
    v |= uint64_t((data[bit / 8] >> (bit % 8)) & 1u) << i;
  }
  return v;
}

uint8_t e2e_crc(uint16_t data_id, const uint8_t* payload, size_t len) {
  uint8_t crc = 0xFF;
  auto step = [&](uint8_t byte) {
    crc ^= byte;
    for (int k = 0; k < 8; ++k) crc = (crc & 0x80) ? uint8_t((crc << 1) ^ 0x1D) : uint8_t(crc << 1);
  };
  step(uint8_t(data_id & 0xFF));
  step(uint8_t(data_id >> 8));
  for (size_t i = 1; i < len; ++i) step(payload[i]);
  return uint8_t(crc ^ 0xFF);
}

namespace {

// Every signal of one estimate as raw integers, and what saturation did to validity.
struct PackedPose {
  Packed x, y, z, qw, qx, qy, qz, sigma_pos, sigma_yaw;
  uint16_t flags;
  bool valid;
};

PackedPose pack_pose(const PoseSignals& s, double pos_scale, int xy_bits, int z_bits) {
  PackedPose p;
  p.x = pack_signed(s.x, pos_scale, xy_bits);
  p.y = pack_signed(s.y, pos_scale, xy_bits);
  p.z = pack_signed(s.z, pos_scale, z_bits);
  p.qw = pack_signed(s.qw, kQuatScale, 16);
  p.qx = pack_signed(s.qx, kQuatScale, 16);
  p.qy = pack_signed(s.qy, kQuatScale, 16);
  p.qz = pack_signed(s.qz, kQuatScale, 16);
  p.sigma_pos = pack_unsigned(s.sigma_pos_m, 0.01, 16);
  p.sigma_yaw = pack_unsigned(s.sigma_yaw_deg, 0.1, 8);
  const bool sat = p.x.saturated || p.y.saturated || p.z.saturated || p.qw.saturated ||
                   p.qx.saturated || p.qy.saturated || p.qz.saturated || p.sigma_pos.saturated ||
                   p.sigma_yaw.saturated;
  p.flags = uint16_t(s.flags | (sat ? kFlagSaturated : 0));
  p.valid = s.valid && p.flags == 0;
  return p;
}

// State, Flags, Valid at bits 12..32 (status message and FD frame alike).
void put_status(uint8_t* data, const PoseSignals& s, const PackedPose& p) {
  put_bits(data, 12, 4, s.state);
  put_bits(data, 16, 16, p.flags);
  put_bits(data, 32, 1, p.valid ? 1 : 0);
}

}  // namespace

int encode_classic(const PoseSignals& s, uint8_t counter, const Ids& ids,
                   Frame out[kClassicFrames]) {
  const PackedPose p = pack_pose(s, 0.01, 24, 16);
  for (int i = 0; i < kClassicFrames; ++i) {
    out[i] = Frame{};
    out[i].len = 8;
  }
  out[0].id = ids.status;
  put_status(out[0].data, s, p);
  put_bits(out[0].data, 40, 16, uint64_t(p.sigma_pos.raw));
  put_bits(out[0].data, 56, 8, uint64_t(p.sigma_yaw.raw));
  out[1].id = ids.pos_xy;
  put_bits(out[1].data, 16, 24, uint64_t(p.x.raw));
  put_bits(out[1].data, 40, 24, uint64_t(p.y.raw));
  out[2].id = ids.pos_zqw;
  put_bits(out[2].data, 16, 16, uint64_t(p.z.raw));
  put_bits(out[2].data, 32, 16, uint64_t(p.qw.raw));
  put_bits(out[2].data, 48, 16, uint64_t(p.qx.raw));
  out[3].id = ids.quat_yz;
  put_bits(out[3].data, 16, 16, uint64_t(p.qy.raw));
  put_bits(out[3].data, 32, 16, uint64_t(p.qz.raw));
  out[4].id = ids.time;
  put_bits(out[4].data, 16, 48, s.timestamp_us & ((uint64_t(1) << 48) - 1));
  for (int i = 0; i < kClassicFrames; ++i) seal(&out[i], counter);
  return kClassicFrames;
}

void encode_fd(const PoseSignals& s, uint8_t counter, const Ids& ids, Frame* out) {
  const PackedPose p = pack_pose(s, 0.001, 32, 32);
  *out = Frame{};
  out->id = ids.fd;
  out->len = kFdLength;
  out->fd = true;
  put_status(out->data, s, p);
  put_bits(out->data, 40, 32, uint64_t(p.x.raw));
  put_bits(out->data, 72, 32, uint64_t(p.y.raw));
  put_bits(out->data, 104, 32, uint64_t(p.z.raw));
  put_bits(out->data, 136, 16, uint64_t(p.qw.raw));
  put_bits(out->data, 152, 16, uint64_t(p.qx.raw));
  put_bits(out->data, 168, 16, uint64_t(p.qy.raw));
  put_bits(out->data, 184, 16, uint64_t(p.qz.raw));
  put_bits(out->data, 200, 16, uint64_t(p.sigma_pos.raw));
  put_bits(out->data, 216, 8, uint64_t(p.sigma_yaw.raw));
  put_bits(out->data, 224, 64, s.timestamp_us);
  seal(out, counter);
}

int Decoder::slot_of(uint32_t id) const {
  const uint32_t all[6] = {ids_.status,  ids_.pos_xy, ids_.pos_zqw,
                           ids_.quat_yz, ids_.time,   ids_.fd};
  for (int i = 0; i < 6; ++i) {
    if (all[i] == id) return i;
  }
  return -1;
}

Decoder::Event Decoder::feed(const Frame& f, PoseSignals* out) {
  const int slot = slot_of(f.id);
  if (slot < 0) return Event::kUnknownId;
  if ((slot < 5 && f.len != 8) || (slot == 5 && f.len != kFdLength)) return Event::kBadLength;
  if (e2e_crc(uint16_t(f.id), f.data, f.len) != f.data[0]) {
    ++crc_errors;
    return Event::kCrcError;
  }
  const uint8_t counter = f.data[1] & 0x0F;
  Event counter_event = Event::kNone;
  if (last_counter_[slot] >= 0) {
    const int delta = (counter - last_counter_[slot] + 16) % 16;
    if (delta == 0) {
      ++repeated;
      return Event::kCounterRepeated;  // a repeated frame is never used
    }
    if (delta > 1) {
      ++skipped;
      counter_event = Event::kCounterSkipped;
    }
  }
  last_counter_[slot] = counter;
  PoseSignals s;
  auto sgn = [&](int start, int len, double scale) {
    return double(sign_extend(get_bits(f.data, start, len), len)) * scale;
  };
  if (slot == 5) {
    s.state = uint8_t(get_bits(f.data, 12, 4));
    s.flags = uint16_t(get_bits(f.data, 16, 16));
    s.valid = get_bits(f.data, 32, 1) != 0;
    s.x = sgn(40, 32, 0.001);
    s.y = sgn(72, 32, 0.001);
    s.z = sgn(104, 32, 0.001);
    s.qw = sgn(136, 16, kQuatScale);
    s.qx = sgn(152, 16, kQuatScale);
    s.qy = sgn(168, 16, kQuatScale);
    s.qz = sgn(184, 16, kQuatScale);
    s.sigma_pos_m = double(get_bits(f.data, 200, 16)) * 0.01;
    s.sigma_yaw_deg = double(get_bits(f.data, 216, 8)) * 0.1;
    s.timestamp_us = get_bits(f.data, 224, 64);
    *out = s;
    ++estimates;
    return Event::kEstimate;
  }
  // Classic: collect the five frames of one counter value.
  if (have_ && counter != group_counter_) {
    ++incomplete;
    have_ = 0;
  }
  group_counter_ = counter;
  group_[slot] = f;
  have_ |= uint8_t(1u << slot);
  if (have_ != 0x1F) return counter_event == Event::kNone ? Event::kNone : counter_event;
  have_ = 0;
  const uint8_t* st = group_[0].data;
  s.state = uint8_t(get_bits(st, 12, 4));
  s.flags = uint16_t(get_bits(st, 16, 16));
  s.valid = get_bits(st, 32, 1) != 0;
  s.sigma_pos_m = double(get_bits(st, 40, 16)) * 0.01;
  s.sigma_yaw_deg = double(get_bits(st, 56, 8)) * 0.1;
  auto sgn_of = [&](int i, int start, int len, double scale) {
    return double(sign_extend(get_bits(group_[i].data, start, len), len)) * scale;
  };
  s.x = sgn_of(1, 16, 24, 0.01);
  s.y = sgn_of(1, 40, 24, 0.01);
  s.z = sgn_of(2, 16, 16, 0.01);
  s.qw = sgn_of(2, 32, 16, kQuatScale);
  s.qx = sgn_of(2, 48, 16, kQuatScale);
  s.qy = sgn_of(3, 16, 16, kQuatScale);
  s.qz = sgn_of(3, 32, 16, kQuatScale);
  s.timestamp_us = get_bits(group_[4].data, 16, 48);
  *out = s;
  ++estimates;
  return Event::kEstimate;
}

const char* event_name(Decoder::Event e) {
  switch (e) {
    case Decoder::Event::kNone: return "none";
    case Decoder::Event::kEstimate: return "estimate";
    case Decoder::Event::kCrcError: return "crc-error";
    case Decoder::Event::kCounterRepeated: return "counter-repeated";
    case Decoder::Event::kCounterSkipped: return "counter-skipped";
    case Decoder::Event::kBadLength: return "bad-length";
    case Decoder::Event::kIncomplete: return "incomplete";
    case Decoder::Event::kUnknownId: return "unknown-id";
  }
  return "?";
}

}  // namespace aprt::can
