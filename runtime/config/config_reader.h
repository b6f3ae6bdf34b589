// Typed reads of the YAML tree with the key path and line in every refusal
// ("aprt.yaml:12: source.replay.rate_hz: expected a number in [0, 1000], got
// 'fast'"): what config.cc's schema is written with.
#pragma once

#include <cerrno>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <initializer_list>
#include <string>

#include "runtime/base/expected.h"
#include "runtime/config/yaml_tree.h"

namespace aprt::config {

using yaml::Node;

class Reader {
 public:
  explicit Reader(const std::string& origin) : origin_(origin) {}

  Error fail(const Node* n, const std::string& path, const std::string& what) const {
    return Error(Errc::kInvalidArgument, "%s:%d: %s: %s", origin_.c_str(), n ? n->line : 0,
                 path.c_str(), what.c_str());
  }

  // `node` must be a map (or absent) with no keys outside `allowed`.
  Status map(const Node* node, const std::string& path,
             std::initializer_list<const char*> allowed) {
    if (!node || node->kind == Node::kNull) return ok();
    if (node->kind != Node::kMap) {
      return fail(node, path.empty() ? "document" : path,
                  path.empty() ? "the document must be a mapping" : "expected a mapping");
    }
    for (const auto& [key, value] : node->map) {
      bool known = false;
      for (const char* a : allowed) known = known || key == a;
      if (!known) {
        std::string list;
        for (const char* a : allowed) list += std::string(list.empty() ? "" : ", ") + a;
        return fail(value.get(), join(path, key.c_str()),
                    "unknown key (expected one of: " + list + ")");
      }
    }
    return ok();
  }

  // non_empty: "" (or a null value) is refused instead of meaning "not set".
  Status str(const Node* m, const std::string& path, const char* key, std::string* out,
             std::initializer_list<const char*> choices = {}, bool non_empty = false) {
    const Node* n = m ? m->get(key) : nullptr;
    if (non_empty && n &&
        (n->kind == Node::kNull || (n->kind == Node::kScalar && n->scalar.empty()))) {
      return fail(n, join(path, key), "must not be empty");
    }
    if (!n || n->kind == Node::kNull) return ok();
    const std::string p = join(path, key);
    if (n->kind != Node::kScalar) return fail(n, p, "expected a string");
    if (choices.size()) {
      bool found = false;
      std::string list;
      for (const char* c : choices) {
        found = found || n->scalar == c;
        list += std::string(list.empty() ? "" : ", ") + c;
      }
      if (!found) return fail(n, p, "'" + n->scalar + "' is not one of: " + list);
    }
    *out = n->scalar;
    return ok();
  }

  Status num(const Node* m, const std::string& path, const char* key, double lo, double hi,
             double* out) {
    const Node* n = m ? m->get(key) : nullptr;
    if (!n || n->kind == Node::kNull) return ok();
    const std::string p = join(path, key);
    char* end = nullptr;
    errno = 0;
    const double v = n->kind == Node::kScalar && !n->quoted && decimal(n->scalar)
                         ? std::strtod(n->scalar.c_str(), &end)
                         : NAN;
    if (n->kind != Node::kScalar || n->quoted || !end || *end || errno || !std::isfinite(v) ||
        v < lo || v > hi) {
      char range[96];
      std::snprintf(range, sizeof range, "expected a number in [%g, %g], got '%s'", lo, hi,
                    n->kind == Node::kScalar ? n->scalar.c_str() : "(not a scalar)");
      return fail(n, p, range);
    }
    *out = v;
    return ok();
  }

  Status integer(const Node* m, const std::string& path, const char* key, long lo, long hi,
                 int* out) {
    const Node* n = m ? m->get(key) : nullptr;
    if (!n || n->kind == Node::kNull) return ok();
    const std::string p = join(path, key);
    char* end = nullptr;
    errno = 0;
    const long v = n->kind == Node::kScalar ? std::strtol(n->scalar.c_str(), &end, 10) : 0;
    if (n->kind != Node::kScalar || n->quoted || !end || *end || errno || v < lo || v > hi ||
        n->scalar.empty()) {
      char range[96];
      std::snprintf(range, sizeof range, "expected an integer in [%ld, %ld], got '%s'", lo, hi,
                    n->kind == Node::kScalar ? n->scalar.c_str() : "(not a scalar)");
      return fail(n, p, range);
    }
    *out = int(v);
    return ok();
  }

  // Decimal or 0x-prefixed hexadecimal (CAN identifiers).
  Status id(const Node* m, const std::string& path, const char* key, long lo, long hi, int* out) {
    const Node* n = m ? m->get(key) : nullptr;
    if (!n || n->kind == Node::kNull) return ok();
    const std::string p = join(path, key);
    const bool hex = n->kind == Node::kScalar && n->scalar.rfind("0x", 0) == 0;
    char* end = nullptr;
    errno = 0;
    const long v =
        n->kind == Node::kScalar ? std::strtol(n->scalar.c_str(), &end, hex ? 16 : 10) : 0;
    if (n->kind != Node::kScalar || n->quoted || !end || *end || errno || v < lo || v > hi ||
        n->scalar.empty()) {
      char range[112];
      std::snprintf(range, sizeof range, "expected an identifier in [0x%lx, 0x%lx], got '%s'", lo,
                    hi, n->kind == Node::kScalar ? n->scalar.c_str() : "(not a scalar)");
      return fail(n, p, range);
    }
    *out = int(v);
    return ok();
  }

  Status vec3(const Node* m, const std::string& path, const char* key, double lo, double hi,
              double out[3]) {
    const Node* n = m ? m->get(key) : nullptr;
    if (!n || n->kind == Node::kNull) return ok();
    const std::string p = join(path, key);
    if (n->kind != Node::kSeq || n->seq.size() != 3)
      return fail(n, p, "expected a list of 3 numbers");
    for (int i = 0; i < 3; ++i) {
      const Node* e = n->seq[size_t(i)].get();
      char* end = nullptr;
      errno = 0;
      const double v = e->kind == Node::kScalar && decimal(e->scalar)
                           ? std::strtod(e->scalar.c_str(), &end)
                           : NAN;
      if (e->kind != Node::kScalar || e->quoted || !end || *end || errno || !std::isfinite(v) ||
          v < lo || v > hi) {
        char range[96];
        std::snprintf(range, sizeof range, "expected a number in [%g, %g]", lo, hi);
        return fail(e, p + "[" + std::to_string(i) + "]", range);
      }
      out[i] = v;
    }
    return ok();
  }

  Status boolean(const Node* m, const std::string& path, const char* key, bool* out) {
    const Node* n = m ? m->get(key) : nullptr;
    if (!n || n->kind == Node::kNull) return ok();
    const std::string p = join(path, key);
    if (n->kind == Node::kScalar && !n->quoted && (n->scalar == "true" || n->scalar == "false")) {
      *out = n->scalar == "true";
      return ok();
    }
    return fail(n, p,
                "expected true or false, got '" +
                    (n->kind == Node::kScalar ? n->scalar : std::string("(not a scalar)")) + "'");
  }

  Status int_list(const Node* m, const std::string& path, const char* key, long lo, long hi,
                  std::vector<int>* out) {
    const Node* n = m ? m->get(key) : nullptr;
    if (!n || n->kind == Node::kNull) return ok();
    const std::string p = join(path, key);
    if (n->kind != Node::kSeq) return fail(n, p, "expected a list of integers");
    out->clear();
    for (size_t i = 0; i < n->seq.size(); ++i) {
      const Node* e = n->seq[i].get();
      char* end = nullptr;
      const long v = e->kind == Node::kScalar ? std::strtol(e->scalar.c_str(), &end, 10) : 0;
      if (e->kind != Node::kScalar || e->quoted || !end || *end || v < lo || v > hi ||
          e->scalar.empty()) {
        return fail(
            e, p + "[" + std::to_string(i) + "]",
            "expected an integer in [" + std::to_string(lo) + ", " + std::to_string(hi) + "]");
      }
      out->push_back(int(v));
    }
    return ok();
  }

  // A plain decimal number: digits, one sign, a point, an exponent -- not
  // strtod's hexadecimal, "inf" or "nan" ("rate_hz: 0x10" is refused).
  static bool decimal(const std::string& s) {
    if (s.empty()) return false;
    for (const char c : s) {
      if (!((c >= '0' && c <= '9') || c == '+' || c == '-' || c == '.' || c == 'e' || c == 'E')) {
        return false;
      }
    }
    return true;
  }

  static std::string join(const std::string& path, const char* key) {
    return path.empty() ? std::string(key) : path + "." + key;
  }

 private:
  std::string origin_;
};

}  // namespace aprt::config
