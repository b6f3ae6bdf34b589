// A YAML document as a small tree with source lines, parsed with libyaml.
// Configuration is read once at start-up (allocation allowed there); the
// typed config (config.h) validates it against the schema with messages
// naming the key path and line.
#pragma once

#include <map>
#include <memory>
#include <string>
#include <vector>

#include "runtime/base/expected.h"

namespace aprt::yaml {

struct Node {
  enum Kind { kScalar, kMap, kSeq, kNull } kind = kNull;
  int line = 0;  // 1-based
  std::string scalar;
  bool quoted = false;
  std::vector<std::pair<std::string, std::unique_ptr<Node>>> map;  // in file order
  std::vector<std::unique_ptr<Node>> seq;

  const Node* get(const std::string& key) const;
};

// A configuration file is at most this large (a regular file: a FIFO or a
// device at the path is refused).
inline constexpr size_t kMaxConfigBytes = size_t(1) << 20;

// Parses text; errors name the file (`origin`) and line. Nesting deeper than
// 32 levels, aliases, tags other than !!str and duplicate keys are refused.
Expected<std::unique_ptr<Node>> parse(const std::string& text, const std::string& origin);
Expected<std::unique_ptr<Node>> parse_file(const std::string& path);

}  // namespace aprt::yaml
