// Minimal, strict command-line parsing: unknown options are errors.
#pragma once

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
          error_ = name;
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
    const long x = std::strtol(v, &end, 10);
    if (!end || *end || x < lo || x > hi) {
      error_ = name;
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

  const char* error() const { return error_; }

 private:
  int argc_;
  char** argv_;
  const char* error_ = nullptr;
};

}  // namespace aprt::cli
