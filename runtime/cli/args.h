// Minimal, strict command-line parsing: unknown options are errors, and every
// refusal names the argument ("aprt eval: --limit: expected an integer in
// [0, 100000000], got '-5'"; "aprt info: unknown option '--bogus'").
#pragma once

#include <cerrno>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>

namespace aprt::cli {

class Args {
 public:
  Args(int argc, char** argv) : argc_(argc), argv_(argv) {}

  // Consumes "--name" (flag). Returns true when present.
  bool flag(const char* name) {
    for (int i = 1; i < argc_; ++i) {
      if (argv_[i] && std::strcmp(argv_[i], name) == 0) {
        argv_[i] = nullptr;
        return true;
      }
    }
    return false;
  }

  // Consumes "--name VALUE"; returns VALUE or `fallback`. Sets error() when the value is missing.
  const char* value(const char* name, const char* fallback = nullptr) {
    for (int i = 1; i < argc_; ++i) {
      if (argv_[i] && std::strcmp(argv_[i], name) == 0) {
        argv_[i] = nullptr;
        if (i + 1 >= argc_ || !argv_[i + 1]) {
          fail(name, "expects a value");
          return fallback;
        }
        const char* v = argv_[i + 1];
        argv_[i + 1] = nullptr;
        return v;
      }
    }
    return fallback;
  }

  long integer(const char* name, long fallback, long lo, long hi) {
    const char* v = value(name);
    if (!v) return fallback;
    char* end = nullptr;
    errno = 0;
    const long x = std::strtol(v, &end, 10);
    if (end == v || !end || *end || errno || x < lo || x > hi) {
      char why[160];
      std::snprintf(why, sizeof why, "expected an integer in [%ld, %ld], got '%.60s'", lo, hi, v);
      fail(name, why);
      return fallback;
    }
    return x;
  }

  double number(const char* name, double fallback, double lo, double hi) {
    const char* v = value(name);
    if (!v) return fallback;
    char* end = nullptr;
    errno = 0;
    const double x = std::strtod(v, &end);
    if (end == v || !end || *end || errno || !std::isfinite(x) || x < lo || x > hi) {
      char why[160];
      std::snprintf(why, sizeof why, "expected a number in [%g, %g], got '%.60s'", lo, hi, v);
      fail(name, why);
      return fallback;
    }
    return x;
  }

  // The remaining positional arguments, in order; nullptr when exhausted.
  const char* positional() {
    for (int i = 1; i < argc_; ++i) {
      if (argv_[i] && argv_[i][0] != '-') {
        const char* v = argv_[i];
        argv_[i] = nullptr;
        return v;
      }
    }
    return nullptr;
  }

  // The first argument nothing consumed (an unknown option), or nullptr.
  const char* leftover() const {
    for (int i = 1; i < argc_; ++i) {
      if (argv_[i]) return argv_[i];
    }
    return nullptr;
  }

  const char* error() const { return error_ ? message_ : nullptr; }

  // Prints why the arguments are refused, as "aprt COMMAND: ...", and returns
  // true; false when they are fine (every value parsed, nothing left over).
  bool refuse(const char* command) const {
    if (error_) {
      std::fprintf(stderr, "aprt %s: %s\n", command, message_);
      return true;
    }
    if (const char* rest = leftover()) {
      std::fprintf(stderr, "aprt %s: %s '%s' (aprt %s --help)\n", command,
                   rest[0] == '-' ? "unknown option" : "unexpected argument", rest, command);
      return true;
    }
    return false;
  }

 private:
  void fail(const char* name, const char* why) {
    if (error_) return;  // the first refusal is the one reported
    error_ = name;
    std::snprintf(message_, sizeof message_, "%s: %s", name, why);
  }

  int argc_;
  char** argv_;
  const char* error_ = nullptr;
  char message_[256] = {};
};

}  // namespace aprt::cli
