// A reader for the subset of the DBC format aprt's pose file and a vehicle's
// odometry signals use (BO_, SG_ with Intel/Motorola byte order,
// signed/unsigned, factor/offset, range, unit, multiplexer indicators; VAL_
// tables); other sections (CM_, BA_, ...) are skipped. The decoder tool
// decodes frames with it, so what it prints is what the DBC file says, not
// what the encoder assumes; the tests cross-check the encoder against it.
// Parsing allocates (start-up, offline tools); raw() and physical() do not:
// the odometry reader (drivers/input/can_odometry) decodes with them live.
#pragma once

#include <cstdint>
#include <map>
#include <string>
#include <vector>

#include "runtime/base/expected.h"

namespace aprt::can {

struct DbcSignal {
  std::string name;
  int start = 0, length = 0;
  bool little_endian = true, is_signed = false;
  double factor = 1, offset = 0, min = 0, max = 0;
  std::string unit;
  std::map<int64_t, std::string> values;  // VAL_ table
  bool multiplexor = false;               // "M": selects which multiplexed signals a frame carries
  int mux_value = -1;  // "m<k>": present only when the multiplexor is k (-1: always)

  // Raw bits of the signal in `data` (length bytes valid).
  uint64_t raw(const uint8_t* data, size_t length) const noexcept;
  // The raw bits as the integer they are (sign-extended when signed): what
  // VAL_ tables and value lists count.
  int64_t integer(const uint8_t* data, size_t length) const noexcept;
  double physical(const uint8_t* data, size_t length) const noexcept;
  // Bytes a frame must have to carry every bit of the signal (either byte order).
  int bytes_spanned() const noexcept;
};

struct DbcMessage {
  uint32_t id = 0;
  std::string name;
  int length = 0;
  std::string sender;
  std::vector<DbcSignal> signals;
  const DbcSignal* signal(const std::string& name) const;
};

struct Dbc {
  std::vector<DbcMessage> messages;
  const DbcMessage* message(uint32_t id) const;
  const DbcMessage* message(const std::string& name) const;
};

Expected<Dbc> parse_dbc(const std::string& text, const std::string& origin);
Expected<Dbc> load_dbc(const std::string& path);

}  // namespace aprt::can
