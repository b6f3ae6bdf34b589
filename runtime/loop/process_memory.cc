#include "runtime/loop/process_memory.h"

#include <fcntl.h>
#include <pthread.h>
#include <unistd.h>

#include <cerrno>
#include <cstdio>
#include <cstdlib>
#include <cstring>

#if defined(__GLIBC__)
#include <malloc.h>
#endif

namespace aprt {

size_t thread_stack_bytes(const Config::Threads& t) {
  size_t bytes = size_t(t.stack_kib) * 1024;
#if defined(__SANITIZE_ADDRESS__) || defined(__SANITIZE_THREAD__)
  bytes *= 4;
#endif
  return bytes;
}

void bound_process_memory(const Config::Threads& t) {
#if defined(__GLIBC__)
  pthread_attr_t attr;
  if (pthread_attr_init(&attr) == 0) {
    const int rc = pthread_attr_setstacksize(&attr, thread_stack_bytes(t));
    if (rc != 0 || pthread_setattr_default_np(&attr) != 0) {
      std::fprintf(stderr, "aprt run: warning: cannot set the threads' stack size to %d KiB (%s)\n",
                   t.stack_kib, std::strerror(rc ? rc : EINVAL));
    }
    pthread_attr_destroy(&attr);
  }
  if (mallopt(M_ARENA_MAX, 1) != 1) {
    std::fprintf(stderr, "aprt run: warning: cannot limit malloc to one arena\n");
  }
#else
  (void)t;  // other C libraries: stacks set per thread by start_thread only
#endif
}

namespace {

// One mapping of smaps: its header line, then "Key: value kB" lines.
struct Mapping {
  uintptr_t begin = 0, end = 0;
  bool anonymous = false, file = false, stack = false;
  uint64_t rss_kb = 0, locked_kb = 0;
};

void add(const Mapping& m, const void* block, size_t block_bytes, size_t stack_bytes,
         MemoryBudget* b) {
  if (m.end == 0) return;
  b->total_kb += m.rss_kb;
  b->locked_kb += m.locked_kb;
  const auto at = reinterpret_cast<uintptr_t>(block);
  const size_t size = m.end - m.begin;
  if (block && m.begin < at + block_bytes && at < m.end) {  // the block, in one mapping or more
    b->engine_kb += m.rss_kb;
  } else if (m.file) {
    b->code_kb += m.rss_kb;
  } else if (m.stack ||
             (m.anonymous && stack_bytes &&
              (size == stack_bytes || size + size_t(sysconf(_SC_PAGESIZE)) == stack_bytes))) {
    b->stacks_kb += m.rss_kb;
    ++b->stacks;
  } else {
    b->other_kb += m.rss_kb;
  }
}

// A header line: "begin-end perms offset dev inode [path]".
bool parse_header(const char* line, Mapping* m) {
  char* p = nullptr;
  const unsigned long long begin = std::strtoull(line, &p, 16);
  if (*p != '-') return false;
  const unsigned long long end = std::strtoull(p + 1, &p, 16);
  if (*p != ' ') return false;
  *m = Mapping{};
  m->begin = uintptr_t(begin);
  m->end = uintptr_t(end);
  // Skip perms, offset, dev, inode to the path.
  const char* q = p;
  for (int field = 0; field < 4 && *q; ++field) {
    while (*q == ' ') ++q;
    while (*q && *q != ' ') ++q;
  }
  while (*q == ' ') ++q;
  m->file = *q == '/';
  m->stack = std::strncmp(q, "[stack]", 7) == 0;
  m->anonymous = *q == '\0';
  return true;
}

}  // namespace

bool measure_memory(const void* engine_block, size_t engine_bytes, size_t stack_bytes,
                    MemoryBudget* out) {
  *out = MemoryBudget{};
  const int fd = open("/proc/self/smaps", O_RDONLY | O_CLOEXEC);
  if (fd < 0) return false;
  char buf[8192];
  size_t have = 0;
  Mapping m;
  bool eof = false;
  while (!eof || have > 0) {
    if (!eof && have < sizeof buf - 1) {
      const ssize_t got = read(fd, buf + have, sizeof buf - 1 - have);
      if (got <= 0)
        eof = true;
      else
        have += size_t(got);
    }
    buf[have] = '\0';
    char* nl = std::strchr(buf, '\n');
    if (!nl) {
      if (!eof && have < sizeof buf - 1) continue;
      nl = buf + have;  // the last line, or one longer than the buffer: taken as is
    }
    *nl = '\0';
    const char* line = buf;
    if (std::strncmp(line, "Rss:", 4) == 0) {
      m.rss_kb = std::strtoull(line + 4, nullptr, 10);
    } else if (std::strncmp(line, "Locked:", 7) == 0) {
      m.locked_kb = std::strtoull(line + 7, nullptr, 10);
    } else if ((line[0] >= '0' && line[0] <= '9') || (line[0] >= 'a' && line[0] <= 'f')) {
      Mapping next;
      if (parse_header(line, &next)) {
        add(m, engine_block, engine_bytes, stack_bytes, out);
        m = next;
      }
    }
    const size_t used = size_t(nl - buf) + (nl < buf + have ? 1 : 0);
    std::memmove(buf, buf + used, have - used);
    have -= used;
  }
  add(m, engine_block, engine_bytes, stack_bytes, out);
  close(fd);
  return out->total_kb > 0;
}

void memory_budget_text(const MemoryBudget& b, char* buf, size_t n) {
  auto mb = [](uint64_t kb) { return double(kb) * 1024.0 / 1e6; };
  std::snprintf(buf, n,
                "RSS %.1f MB = engine block %.1f + program and libraries %.1f + %u stacks %.1f + "
                "heap and other %.1f; locked %.1f MB",
                mb(b.total_kb), mb(b.engine_kb), mb(b.code_kb), b.stacks, mb(b.stacks_kb),
                mb(b.other_kb), mb(b.locked_kb));
}

}  // namespace aprt
