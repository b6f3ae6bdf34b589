#include "runtime/base/text_lines.h"

#include <cerrno>
#include <cmath>
#include <cstdlib>
#include <cstring>

#include "runtime/base/check.h"

namespace aprt {

Status check_text_line(std::string_view line, const char* what, const char* path, int lineno) {
  APRT_ENSURE(line.size() < kMaxTextLine, Errc::kBadMetadata,
              "%s: %s:%d: a line of %zu bytes (at most %zu)", what, path, lineno, line.size(),
              kMaxTextLine - 1);
  APRT_ENSURE(line.find('\0') == std::string_view::npos, Errc::kBadMetadata,
              "%s: %s:%d: a NUL byte in a text file", what, path, lineno);
  return ok();
}

int split_fields(char* line, char** out, int max) {
  int n = 0;
  char* save = nullptr;
  for (char* t = strtok_r(line, " \t\r", &save); t; t = strtok_r(nullptr, " \t\r", &save)) {
    if (n == max) return max + 1;
    out[n++] = t;
  }
  return n;
}

bool parse_finite(const char* s, double* out) {
  char* end = nullptr;
  errno = 0;
  const double d = std::strtod(s, &end);
  if (end == s || *end != '\0' || errno == ERANGE || !std::isfinite(d)) return false;
  *out = d;
  return true;
}

bool parse_integer(const char* s, int64_t lo, int64_t hi, int64_t* out) {
  // Decimal digits only (strtoll alone takes blanks, '+', and would wrap).
  const char* p = s + (*s == '-' ? 1 : 0);
  if (*p == '\0' || std::strspn(p, "0123456789") != std::strlen(p)) return false;
  char* end = nullptr;
  errno = 0;
  const long long v = std::strtoll(s, &end, 10);
  if (errno == ERANGE || *end != '\0' || v < lo || v > hi) return false;
  *out = v;
  return true;
}

}  // namespace aprt
