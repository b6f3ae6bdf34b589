// Line-oriented text files of outside origin (pose lists, times, frame
// sidecars, candump logs): lines split without trusting the text (a bounded
// line length, no NUL bytes), fields split on blanks, numbers that must parse
// whole. Each parser built on these is fuzzed (tests/fuzz/).
#pragma once

#include <cstddef>
#include <cstdint>
#include <string_view>

#include "runtime/base/expected.h"

namespace aprt {

inline constexpr size_t kMaxTextLine = 1024;

// fn(char* line, int lineno) -> Status for each line of `text` that is not
// blank and (when `comments`) does not start with '#'; the line is a
// NUL-terminated copy fn may modify. A line of kMaxTextLine bytes or more, or
// one holding a NUL byte, is an error naming `what`, `path` and the line;
// the first error fn returns ends the walk.
Status check_text_line(std::string_view line, const char* what, const char* path, int lineno);
template <class Fn>
Status each_text_line(std::string_view text, const char* what, const char* path, bool comments,
                      Fn fn) {
  int lineno = 0;
  size_t pos = 0;
  while (pos < text.size()) {
    const size_t nl = text.find('\n', pos);
    const std::string_view line = text.substr(pos, nl == std::string_view::npos ? nl : nl - pos);
    pos = nl == std::string_view::npos ? text.size() : nl + 1;
    ++lineno;
    if (Status s = check_text_line(line, what, path, lineno); !s) return s;
    size_t a = 0;
    while (a < line.size() && (line[a] == ' ' || line[a] == '\t' || line[a] == '\r')) ++a;
    if (a == line.size() || (comments && line[a] == '#')) continue;
    char buf[kMaxTextLine];
    line.copy(buf, line.size());
    buf[line.size()] = '\0';
    if (Status s = fn(buf, lineno); !s) return s;
  }
  return ok();
}

// Splits `line` in place on blanks into out[0..]; returns the count, or
// max + 1 when there are more than `max` fields.
int split_fields(char* line, char** out, int max);

// The whole of `s` as a finite double / a decimal integer in [lo, hi].
bool parse_finite(const char* s, double* out);
bool parse_integer(const char* s, int64_t lo, int64_t hi, int64_t* out);

}  // namespace aprt
