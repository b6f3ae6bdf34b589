#include "runtime/config/yaml_tree.h"

#include <yaml.h>

#include <cstdio>
#include <cstring>
#include <unordered_set>

#include "runtime/base/file_io.h"

namespace aprt::yaml {

const Node* Node::get(const std::string& key) const {
  for (const auto& [k, v] : map) {
    if (k == key) return v.get();
  }
  return nullptr;
}

namespace {

struct Parser {
  yaml_parser_t p;
  std::string origin;
  std::string error;

  bool next(yaml_event_t* e) {
    if (!yaml_parser_parse(&p, e)) {
      char buf[256];
      std::snprintf(buf, sizeof buf, "%s:%zu: YAML syntax error: %s", origin.c_str(),
                    p.problem_mark.line + 1, p.problem ? p.problem : "unknown");
      error = buf;
      return false;
    }
    return true;
  }

  std::nullptr_t fail(int line, const char* what) {
    char buf[256];
    std::snprintf(buf, sizeof buf, "%s:%d: %s", origin.c_str(), line, what);
    error = buf;
    return nullptr;
  }

  // The one tag a configuration may use: !!str, to make a scalar a string
  // ("!!str 1"). Any other tag would change a value's meaning unseen.
  const char* tag_problem(const yaml_char_t* tag, bool scalar) const {
    if (!tag) return nullptr;
    if (scalar && std::strcmp(reinterpret_cast<const char*>(tag), "tag:yaml.org,2002:str") == 0) {
      return nullptr;
    }
    return "YAML tags are not supported (only !!str on a scalar)";
  }

  // Builds the node the event `e` starts (e is consumed), at most kMaxDepth
  // levels deep (the builder recurses).
  static constexpr int kMaxDepth = 32;
  std::unique_ptr<Node> node(yaml_event_t& e, int depth = 0) {
    auto n = std::make_unique<Node>();
    n->line = int(e.start_mark.line) + 1;
    if (depth > kMaxDepth) {
      yaml_event_delete(&e);
      return fail(n->line, "nesting deeper than 32 levels");
    }
    const yaml_char_t* tag = e.type == YAML_SCALAR_EVENT           ? e.data.scalar.tag
                             : e.type == YAML_SEQUENCE_START_EVENT ? e.data.sequence_start.tag
                             : e.type == YAML_MAPPING_START_EVENT  ? e.data.mapping_start.tag
                                                                   : nullptr;
    if (const char* why = tag_problem(tag, e.type == YAML_SCALAR_EVENT)) {
      yaml_event_delete(&e);
      return fail(n->line, why);
    }
    switch (e.type) {
      case YAML_SCALAR_EVENT: {
        n->kind = Node::kScalar;
        n->scalar.assign(reinterpret_cast<const char*>(e.data.scalar.value), e.data.scalar.length);
        // Quoted, or tagged !!str: a string, never a number or null.
        n->quoted = e.data.scalar.style == YAML_SINGLE_QUOTED_SCALAR_STYLE ||
                    e.data.scalar.style == YAML_DOUBLE_QUOTED_SCALAR_STYLE || tag != nullptr;
        if (!n->quoted && (n->scalar == "~" || n->scalar == "null" || n->scalar.empty())) {
          n->kind = Node::kNull;
        }
        yaml_event_delete(&e);
        return n;
      }
      case YAML_SEQUENCE_START_EVENT: {
        n->kind = Node::kSeq;
        yaml_event_delete(&e);
        for (;;) {
          yaml_event_t c;
          if (!next(&c)) return nullptr;
          if (c.type == YAML_SEQUENCE_END_EVENT) {
            yaml_event_delete(&c);
            return n;
          }
          auto child = node(c, depth + 1);
          if (!child) return nullptr;
          n->seq.push_back(std::move(child));
        }
      }
      case YAML_MAPPING_START_EVENT: {
        n->kind = Node::kMap;
        yaml_event_delete(&e);
        std::unordered_set<std::string> keys;  // a duplicate check in constant time per key
        for (;;) {
          yaml_event_t k;
          if (!next(&k)) return nullptr;
          if (k.type == YAML_MAPPING_END_EVENT) {
            yaml_event_delete(&k);
            return n;
          }
          if (k.type != YAML_SCALAR_EVENT) {
            char buf[256];
            std::snprintf(buf, sizeof buf, "%s:%zu: mapping keys must be plain scalars",
                          origin.c_str(), k.start_mark.line + 1);
            error = buf;
            yaml_event_delete(&k);
            return nullptr;
          }
          std::string key(reinterpret_cast<const char*>(k.data.scalar.value), k.data.scalar.length);
          const int key_line = int(k.start_mark.line) + 1;
          yaml_event_delete(&k);
          if (!keys.insert(key).second) {
            char buf[256];
            std::snprintf(buf, sizeof buf, "%s:%d: key '%.120s' appears twice", origin.c_str(),
                          key_line, key.c_str());
            error = buf;
            return nullptr;
          }
          yaml_event_t v;
          if (!next(&v)) return nullptr;
          auto child = node(v, depth + 1);
          if (!child) return nullptr;
          n->map.emplace_back(std::move(key), std::move(child));
        }
      }
      case YAML_ALIAS_EVENT: {
        char buf[256];
        std::snprintf(buf, sizeof buf, "%s:%d: YAML aliases are not supported", origin.c_str(),
                      n->line);
        error = buf;
        yaml_event_delete(&e);
        return nullptr;
      }
      default: yaml_event_delete(&e); return n;
    }
  }
};

}  // namespace

Expected<std::unique_ptr<Node>> parse(const std::string& text, const std::string& origin) {
  Parser ps;
  ps.origin = origin;
  yaml_parser_initialize(&ps.p);
  yaml_parser_set_input_string(&ps.p, reinterpret_cast<const unsigned char*>(text.data()),
                               text.size());
  std::unique_ptr<Node> root;
  yaml_event_t e;
  bool ok = true;
  while (ok && (ok = ps.next(&e))) {
    const auto type = e.type;
    if (type == YAML_STREAM_END_EVENT) {
      yaml_event_delete(&e);
      break;
    }
    if (type == YAML_STREAM_START_EVENT || type == YAML_DOCUMENT_START_EVENT ||
        type == YAML_DOCUMENT_END_EVENT) {
      yaml_event_delete(&e);
      continue;
    }
    if (root) {
      yaml_event_delete(&e);
      ps.error = origin + ": more than one YAML document";
      ok = false;
      break;
    }
    root = ps.node(e);
    ok = root != nullptr;
  }
  yaml_parser_delete(&ps.p);
  if (!ok) return Error(Errc::kInvalidArgument, "%s", ps.error.c_str());
  if (!root) root = std::make_unique<Node>();  // empty document
  return root;
}

Expected<std::unique_ptr<Node>> parse_file(const std::string& path) {
  std::string text;
  if (Status s = read_input_file(path.c_str(), kMaxConfigBytes, "config", &text); !s) {
    return s.error();
  }
  return parse(text, path);
}

}  // namespace aprt::yaml
