#include "drivers/output/can/candump_log.h"

#include <cmath>
#include <cstdlib>
#include <cstring>

#include "runtime/base/check.h"

namespace aprt::can {
namespace {

constexpr uint32_t kEffFlag = 0x80000000u, kRtrFlag = 0x40000000u, kErrFlag = 0x20000000u;

int nibble(char c) {
  if (c >= '0' && c <= '9') return c - '0';
  if (c >= 'a' && c <= 'f') return c - 'a' + 10;
  if (c >= 'A' && c <= 'F') return c - 'A' + 10;
  return -1;
}

bool fd_length(int n) {
  return n <= 8 || n == 12 || n == 16 || n == 20 || n == 24 || n == 32 || n == 48 || n == 64;
}

bool blank(char c) {
  return c == ' ' || c == '\t' || c == '\r';
}

// The next blank-separated token of `s` from *pos.
std::string_view token(std::string_view s, size_t* pos) {
  size_t a = *pos;
  while (a < s.size() && blank(s[a])) ++a;
  size_t b = a;
  while (b < s.size() && !blank(s[b])) ++b;
  *pos = b;
  return s.substr(a, b - a);
}

// A CAN id of 3 hex digits (standard, <= 0x7FF) or 8 (extended; the error
// flag allowed, as candump writes error frames).
Status parse_id(std::string_view s, Frame* f) {
  APRT_ENSURE(s.size() == 3 || s.size() == 8, Errc::kInvalidArgument,
              "candump log: id '%.*s' is not 3 or 8 hex digits", int(s.size()), s.data());
  uint32_t id = 0;
  for (char c : s) {
    const int v = nibble(c);
    APRT_ENSURE(v >= 0, Errc::kInvalidArgument, "candump log: id '%.*s' is not hex", int(s.size()),
                s.data());
    id = id << 4 | uint32_t(v);
  }
  if (s.size() == 3) {
    APRT_ENSURE(id <= 0x7FF, Errc::kInvalidArgument, "candump log: standard id 0x%X above 0x7FF",
                unsigned(id));
  } else {
    APRT_ENSURE((id & (kEffFlag | kRtrFlag)) == 0 && id <= (kErrFlag | 0x1FFFFFFFu),
                Errc::kInvalidArgument, "candump log: extended id 0x%08X out of range",
                unsigned(id));
  }
  f->id = id;
  return ok();
}

// "HHHH..." into f->data.
Status parse_bytes(std::string_view s, Frame* f) {
  APRT_ENSURE(s.size() % 2 == 0, Errc::kInvalidArgument,
              "candump log: data '%.*s' has an odd number of hex digits", int(s.size()), s.data());
  const size_t n = s.size() / 2;
  APRT_ENSURE(n <= (f->fd ? 64u : 8u) && (!f->fd || fd_length(int(n))), Errc::kInvalidArgument,
              "candump log: %zu data bytes (%s)", n,
              f->fd ? "CAN FD has 0-8, 12, 16, 20, 24, 32, 48 or 64" : "at most 8 in classic CAN");
  for (size_t i = 0; i < n; ++i) {
    const int hi = nibble(s[2 * i]), lo = nibble(s[2 * i + 1]);
    APRT_ENSURE(hi >= 0 && lo >= 0, Errc::kInvalidArgument, "candump log: data '%.*s' is not hex",
                int(s.size()), s.data());
    f->data[i] = uint8_t(hi * 16 + lo);
  }
  f->len = uint8_t(n);
  return ok();
}

// "(1700000000.123456)": candump -L always, candump -ta before the default format.
Status parse_stamp(std::string_view stamp, double* t) {
  APRT_ENSURE(stamp.size() >= 3 && stamp.size() < 40 && stamp.front() == '(' && stamp.back() == ')',
              Errc::kInvalidArgument, "candump log: '%.*s' is not a (seconds) time",
              int(stamp.size()), stamp.data());
  char num[40];
  stamp.substr(1, stamp.size() - 2).copy(num, stamp.size() - 2);
  num[stamp.size() - 2] = '\0';
  char* end = nullptr;
  *t = std::strtod(num, &end);
  APRT_ENSURE(end != num && *end == '\0' && std::isfinite(*t) && *t >= 0 &&
                  std::strspn(num, "0123456789.") == std::strlen(num),
              Errc::kInvalidArgument, "candump log: '%s' is not a time in seconds", num);
  return ok();
}

// "can0 301#0011" / "can0 310##1<data>" / "can0 301#R" (after the time).
Status parse_compact(std::string_view line, Frame* f) {
  size_t pos = 0;
  const std::string_view iface = token(line, &pos);
  APRT_ENSURE(!iface.empty() && iface.size() < 16, Errc::kInvalidArgument,
              "candump log: no interface name");
  const std::string_view frame = token(line, &pos);
  APRT_ENSURE(token(line, &pos).empty(), Errc::kInvalidArgument,
              "candump log: trailing text after the frame");
  const size_t hash = frame.find('#');
  APRT_ENSURE(hash != std::string_view::npos, Errc::kInvalidArgument,
              "candump log: frame '%.*s' has no '#'", int(frame.size()), frame.data());
  if (Status s = parse_id(frame.substr(0, hash), f); !s) return s;
  std::string_view data = frame.substr(hash + 1);
  if (!data.empty() && data[0] == '#') {
    APRT_ENSURE(data.size() >= 2 && nibble(data[1]) >= 0, Errc::kInvalidArgument,
                "candump log: CAN FD frame without its flags digit");
    f->fd = true;
    data = data.substr(2);
  } else if (data.size() >= 1 && (data[0] == 'R' || data[0] == 'r')) {
    // A remote frame (optionally with its length digit): no data.
    APRT_ENSURE(
        data.size() == 1 || (data.size() == 2 && nibble(data[1]) >= 0 && nibble(data[1]) <= 8),
        Errc::kInvalidArgument, "candump log: malformed remote frame '%.*s'", int(frame.size()),
        frame.data());
    f->len = 0;
    return ok();
  }
  // Classic frames may carry "_L" (a DLC above 8 for 8 bytes): accept it.
  const size_t us = data.find('_');
  if (us != std::string_view::npos) {
    APRT_ENSURE(!f->fd && us + 2 == data.size() && nibble(data[us + 1]) >= 9,
                Errc::kInvalidArgument, "candump log: malformed length suffix in '%.*s'",
                int(frame.size()), frame.data());
    data = data.substr(0, us);
  }
  return parse_bytes(data, f);
}

// "  can0  301   [8]  00 11 22 ...".
Status parse_spaced(std::string_view line, Frame* f) {
  size_t pos = 0;
  const std::string_view iface = token(line, &pos);
  APRT_ENSURE(!iface.empty() && iface.size() < 16, Errc::kInvalidArgument,
              "candump log: no interface name");
  if (Status s = parse_id(token(line, &pos), f); !s) return s;
  const std::string_view len = token(line, &pos);
  APRT_ENSURE(
      len.size() >= 3 && len.size() <= 4 && len.front() == '[' && len.back() == ']' &&
          nibble(len[1]) >= 0 && nibble(len[1]) <= 9 && (len.size() == 3 || nibble(len[2]) <= 9),
      Errc::kInvalidArgument, "candump log: '%.*s' is not a [length]", int(len.size()), len.data());
  const int n = len.size() == 3 ? len[1] - '0' : (len[1] - '0') * 10 + (len[2] - '0');
  f->fd = n > 8;
  APRT_ENSURE(fd_length(n) && n <= 64, Errc::kInvalidArgument,
              "candump log: length %d is no CAN frame's", n);
  int got = 0;
  for (std::string_view b = token(line, &pos); !b.empty(); b = token(line, &pos)) {
    APRT_ENSURE(got < n, Errc::kInvalidArgument, "candump log: more bytes than [%d]", n);
    APRT_ENSURE(b.size() == 2 && nibble(b[0]) >= 0 && nibble(b[1]) >= 0, Errc::kInvalidArgument,
                "candump log: data byte '%.*s' is not two hex digits", int(b.size()), b.data());
    f->data[got++] = uint8_t(nibble(b[0]) * 16 + nibble(b[1]));
  }
  APRT_ENSURE(got == n, Errc::kInvalidArgument, "candump log: %d bytes where [%d] says %d", got, n,
              n);
  f->len = uint8_t(n);
  return ok();
}

}  // namespace

Expected<LogLine> parse_candump_line(std::string_view line, Frame* f, double* t) {
  *f = Frame{};
  *t = 0;
  size_t a = 0;
  while (a < line.size() && blank(line[a])) ++a;
  if (a == line.size() || line[a] == '#') return LogLine::kBlank;
  APRT_ENSURE(line.size() < 1024 && std::memchr(line.data(), '\0', line.size()) == nullptr,
              Errc::kInvalidArgument, "candump log: not a text line");
  std::string_view rest = line.substr(a);
  if (rest[0] == '(') {
    size_t pos = 0;
    if (Status s = parse_stamp(token(rest, &pos), t); !s) return s.error();
    rest = rest.substr(pos);
  }
  Status s =
      rest.find('#') != std::string_view::npos ? parse_compact(rest, f) : parse_spaced(rest, f);
  if (!s) return s.error();
  return LogLine::kFrame;
}

}  // namespace aprt::can
