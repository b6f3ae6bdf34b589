#include "drivers/can/dbc.h"

#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <sstream>

#include "runtime/base/file_io.h"

namespace aprt::can {

uint64_t DbcSignal::raw(const uint8_t* data, size_t bytes) const noexcept {
  uint64_t v = 0;
  if (little_endian) {
    for (int i = 0; i < length; ++i) {
      const int bit = start + i;
      if (size_t(bit / 8) >= bytes) break;
      v |= uint64_t((data[bit / 8] >> (bit % 8)) & 1u) << i;
    }
  } else {
    // Motorola: `start` is the most significant bit, counting down within a
    // byte and on to the next byte.
    int bit = start;
    for (int i = 0; i < length; ++i) {
      if (size_t(bit / 8) >= bytes) break;
      v = (v << 1) | ((data[bit / 8] >> (bit % 8)) & 1u);
      bit = (bit % 8 == 0) ? bit + 15 : bit - 1;
    }
  }
  return v;
}

int64_t DbcSignal::integer(const uint8_t* data, size_t bytes) const noexcept {
  const uint64_t r = raw(data, bytes);
  if (is_signed && length < 64) {
    const uint64_t m = uint64_t(1) << (length - 1);
    return int64_t((r ^ m) - m);
  }
  return int64_t(r);
}

double DbcSignal::physical(const uint8_t* data, size_t bytes) const noexcept {
  // An unsigned 64-bit value keeps its magnitude; every other is the integer.
  const double v =
      !is_signed && length == 64 ? double(raw(data, bytes)) : double(integer(data, bytes));
  return v * factor + offset;
}

int DbcSignal::bytes_spanned() const noexcept {
  if (little_endian) return (start + length - 1) / 8 + 1;
  // Motorola: from the most significant bit down and on to later bytes,
  // so the last bit walked is in the last byte.
  int bit = start;
  for (int i = 1; i < length; ++i) bit = (bit % 8 == 0) ? bit + 15 : bit - 1;
  return bit / 8 + 1;
}

const DbcSignal* DbcMessage::signal(const std::string& n) const {
  for (const auto& s : signals) {
    if (s.name == n) return &s;
  }
  return nullptr;
}

const DbcMessage* Dbc::message(uint32_t id) const {
  for (const auto& m : messages) {
    if (m.id == id) return &m;
  }
  return nullptr;
}

const DbcMessage* Dbc::message(const std::string& n) const {
  for (const auto& m : messages) {
    if (m.name == n) return &m;
  }
  return nullptr;
}

namespace {

Error bad(const std::string& origin, int line, const char* what) {
  return Error(Errc::kInvalidArgument, "%s:%d: %s", origin.c_str(), line, what);
}

}  // namespace

Expected<Dbc> parse_dbc(const std::string& text, const std::string& origin) {
  Dbc dbc;
  std::istringstream in(text);
  std::string line;
  int lineno = 0;
  DbcMessage* current = nullptr;
  while (std::getline(in, line)) {
    ++lineno;
    const size_t first = line.find_first_not_of(" \t");
    if (first == std::string::npos) {
      current = nullptr;
      continue;
    }
    const std::string body = line.substr(first);
    if (body.rfind("BO_ ", 0) == 0) {
      char name[128], sender[128];
      unsigned long id = 0;
      int length = 0;
      if (std::sscanf(body.c_str(), "BO_ %lu %127[^:]: %d %127s", &id, name, &length, sender) !=
          4) {
        return bad(origin, lineno, "malformed BO_ line (expected: BO_ <id> <name>: <dlc> <node>)");
      }
      // A frame has at most 64 bytes (CAN FD); the signals' bounds are
      // checked against this length in bits.
      if (length < 0 || length > 64) {
        return bad(origin, lineno, "BO_ with a length outside 0..64 bytes");
      }
      DbcMessage m;
      m.id = uint32_t(id & 0x1FFFFFFF);  // bit 31 marks an extended id in DBC
      m.name = name;
      m.length = length;
      m.sender = sender;
      dbc.messages.push_back(m);
      current = &dbc.messages.back();
    } else if (body.rfind("SG_ ", 0) == 0) {
      if (!current) return bad(origin, lineno, "SG_ outside a BO_ block");
      // SG_ name [M|m<k>] : start|length@order sign (factor,offset) [min|max] "unit" receivers
      const size_t colon = body.find(':');
      if (colon == std::string::npos) {
        return bad(origin, lineno, "malformed SG_ line (no ':' after the signal's name)");
      }
      std::istringstream head(body.substr(4, colon - 4));
      std::string name, mux, extra;
      head >> name >> mux >> extra;
      int mux_value = -1;
      bool multiplexor = false;
      if (mux == "M") {
        multiplexor = true;
      } else if (mux.size() >= 2 && mux[0] == 'm') {
        char* end = nullptr;
        const long v = std::strtol(mux.c_str() + 1, &end, 10);
        // "m3M": a multiplexed multiplexor (extended multiplexing): taken as multiplexed.
        if (end == mux.c_str() + 1 || v < 0 || (*end != '\0' && *end != 'M')) {
          return bad(origin, lineno, "SG_ with a malformed multiplexer indicator (M or m<k>)");
        }
        mux_value = int(v);
      } else if (!mux.empty()) {
        return bad(origin, lineno, "SG_ with a malformed multiplexer indicator (M or m<k>)");
      }
      if (name.empty() || name.size() > 127 || !extra.empty()) {
        return bad(origin, lineno, "malformed SG_ line (expected: SG_ name [M|m<k>] : ...)");
      }
      char order_sign[4], unit[64] = "";
      int start = 0, length = 0;
      double factor = 1, offset = 0, lo = 0, hi = 0;
      const int n =
          std::sscanf(body.c_str() + colon, ": %d|%d@%3s (%lf,%lf) [%lf|%lf] \"%63[^\"]\"", &start,
                      &length, order_sign, &factor, &offset, &lo, &hi, unit);
      if (n < 7) {
        return bad(origin, lineno,
                   "malformed SG_ line (expected: SG_ name : start|length@order+/- (factor,offset) "
                   "[min|max] \"unit\" receivers)");
      }
      DbcSignal s;
      s.name = name;
      s.start = start;
      s.length = length;
      s.little_endian = order_sign[0] == '1';
      s.is_signed = order_sign[1] == '-';
      s.factor = factor;
      s.offset = offset;
      s.min = lo;
      s.max = hi;
      s.unit = n >= 8 ? unit : "";
      s.multiplexor = multiplexor;
      s.mux_value = mux_value;
      if (s.bytes_spanned() > current->length) {
        return bad(origin, lineno, "SG_ extends past the message's length");
      }
      current->signals.push_back(s);
    } else if (body.rfind("VAL_ ", 0) == 0) {
      std::istringstream v(body.substr(5));
      unsigned long id;
      std::string sig;
      if (!(v >> id >> sig)) return bad(origin, lineno, "malformed VAL_ line");
      DbcSignal* target = nullptr;
      for (auto& m : dbc.messages) {
        if (m.id == (id & 0x1FFFFFFF)) {
          for (auto& s : m.signals) {
            if (s.name == sig) target = &s;
          }
        }
      }
      if (!target) return bad(origin, lineno, "VAL_ for an unknown message or signal");
      std::string rest;
      std::getline(v, rest);
      const char* p = rest.c_str();
      for (;;) {
        char* end = nullptr;
        const long long key = std::strtoll(p, &end, 10);
        if (end == p) break;
        const char* q1 = std::strchr(end, '"');
        const char* q2 = q1 ? std::strchr(q1 + 1, '"') : nullptr;
        if (!q2) return bad(origin, lineno, "malformed VAL_ description");
        target->values[key] = std::string(q1 + 1, q2);
        p = q2 + 1;
      }
    } else {
      current = nullptr;
    }
  }
  if (dbc.messages.empty())
    return Error(Errc::kInvalidArgument, "%s: no messages (BO_) in the DBC", origin.c_str());
  return dbc;
}

Expected<Dbc> load_dbc(const std::string& path) {
  std::string text;  // a regular file of at most 4 MiB (docs/hostile_input.md)
  if (Status s = read_input_file(path.c_str(), size_t(4) << 20, "dbc", &text); !s) {
    return s.error();
  }
  return parse_dbc(text, path);
}

}  // namespace aprt::can
