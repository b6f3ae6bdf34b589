#include "runtime/loop/timing_report.h"

#include <fcntl.h>
#include <sys/resource.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <string>
#include <vector>

#include "runtime/loop/process_memory.h"
#include "runtime/loop/run_stats.h"

namespace aprt {
namespace {

double at(const std::vector<double>& sorted, double p) {
  return sorted[std::min(sorted.size() - 1, size_t(p * double(sorted.size() - 1) + 0.5))];
}

void put_stage(FILE* f, const char* name, const StageStats& s, bool last) {
  std::fprintf(f,
               "    \"%s\": {\"count\": %zu, \"min\": %.3f, \"median\": %.3f, \"mean\": %.3f, "
               "\"p99\": %.3f, \"p99.9\": %.3f, \"max\": %.3f}%s\n",
               name, s.count, s.min, s.median, s.mean, s.p99, s.p999, s.max, last ? "" : ",");
}

// JSON string content: the paths we print are ours, but a quote or backslash
// in a user's path must not break the report.
std::string escaped(const char* s) {
  std::string out;
  for (; *s; ++s) {
    if (*s == '"' || *s == '\\') out += '\\';
    if (static_cast<unsigned char>(*s) >= 0x20) out += *s;
  }
  return out;
}

// ', "budget_kb": {...}' (where the resident memory is), or nothing.
std::string budget_json(const MemoryBudget* b) {
  if (!b) return "";
  char buf[320];
  std::snprintf(
      buf, sizeof buf,
      ", \"budget_kb\": {\"total\": %llu, \"engine_block\": %llu, "
      "\"program_and_libraries\": %llu, \"stacks\": %llu, \"stack_count\": %u, "
      "\"heap_and_other\": %llu, \"locked\": %llu}",
      static_cast<unsigned long long>(b->total_kb), static_cast<unsigned long long>(b->engine_kb),
      static_cast<unsigned long long>(b->code_kb), static_cast<unsigned long long>(b->stacks_kb),
      b->stacks, static_cast<unsigned long long>(b->other_kb),
      static_cast<unsigned long long>(b->locked_kb));
  return buf;
}

}  // namespace

StageStats stage_stats(const double* values_ms, size_t n) {
  if (n == 0) return {0, 0, 0, 0, 0, 0, 0};
  std::vector<double> v(values_ms, values_ms + n);
  std::sort(v.begin(), v.end());
  double sum = 0;
  for (double x : v) sum += x;
  return {v.front(), at(v, 0.5), at(v, 0.99), at(v, 0.999), v.back(), sum / double(n), n};
}

// open/read into the stack, not stdio: sampled while the loop runs, it must
// not allocate (it would count against the run).
uint64_t current_rss_kb() {
  const int fd = open("/proc/self/statm", O_RDONLY | O_CLOEXEC);
  if (fd < 0) return 0;
  char buf[128];
  const ssize_t got = read(fd, buf, sizeof buf - 1);
  close(fd);
  if (got <= 0) return 0;
  buf[got] = 0;
  char* p = buf;
  std::strtoull(p, &p, 10);  // total program size
  const unsigned long long resident = std::strtoull(p, nullptr, 10);
  return uint64_t(resident) * uint64_t(sysconf(_SC_PAGESIZE)) / 1024;
}

uint64_t peak_rss_kb() {
  rusage ru{};
  return getrusage(RUSAGE_SELF, &ru) == 0 ? uint64_t(ru.ru_maxrss) : 0;
}

Status write_timing_report(const char* json_path, const TimingRecord* records, size_t n,
                           const RunStats& stats, const TimingContext& ctx) {
  std::vector<double> queue(n), infer(n), publish(n), e2e(n);
  for (size_t i = 0; i < n; ++i) {
    const TimingRecord& t = records[i];
    queue[i] = double(t.inference_start_ns - t.capture_ns) * 1e-6;
    infer[i] = double(t.inference_end_ns - t.inference_start_ns) * 1e-6;
    publish[i] = double(t.publish_ns - t.inference_end_ns) * 1e-6;
    e2e[i] = double(t.publish_ns - t.capture_ns) * 1e-6;
  }
  const StageStats sq = stage_stats(queue.data(), n), si = stage_stats(infer.data(), n),
                   sp = stage_stats(publish.data(), n), se = stage_stats(e2e.data(), n);
  // The bound for jitter: p99.9 end to end within 1.05 x median plus one camera period.
  const double bound = 1.05 * se.median + ctx.camera_period_ms;

  FILE* f = std::fopen(json_path, "w");
  if (!f) return Error(Errc::kIo, "timing: cannot write %s: %s", json_path, std::strerror(errno));
  std::fprintf(f, "{\n  \"model\": \"%s\",\n  \"source\": \"%s\",\n", escaped(ctx.model).c_str(),
               escaped(ctx.source).c_str());
  std::fprintf(f, "  \"isa\": \"%s\",\n  \"threads\": %d,\n  \"duration_s\": %.3f,\n", ctx.isa,
               ctx.threads, ctx.duration_s);
  std::fprintf(f,
               "  \"frames\": {\"captured\": %llu, \"skipped\": %llu, \"dropped_stale\": %llu, "
               "\"poses\": %llu, \"flagged\": %llu, \"deadline_misses\": %llu, \"ring_full\": "
               "%llu, \"source_restarts\": %llu, \"timed\": %zu},\n",
               static_cast<unsigned long long>(stats.frames_captured),
               static_cast<unsigned long long>(stats.frames_skipped),
               static_cast<unsigned long long>(stats.frames_dropped),
               static_cast<unsigned long long>(stats.poses),
               static_cast<unsigned long long>(stats.poses_flagged),
               static_cast<unsigned long long>(stats.deadline_misses),
               static_cast<unsigned long long>(stats.ring_full),
               static_cast<unsigned long long>(stats.source_restarts), n);
  std::fprintf(f, "  \"stages_ms\": {\n");
  put_stage(f, "capture_to_inference", sq, false);
  put_stage(f, "inference", si, false);
  put_stage(f, "inference_to_publish", sp, false);
  put_stage(f, "end_to_end", se, true);
  std::fprintf(f, "  },\n");
  std::fprintf(f,
               "  \"jitter\": {\"camera_period_ms\": %.3f, \"inference_deadline_ms\": %.3f, "
               "\"bound_ms\": %.3f, \"p99.9_end_to_end_ms\": %.3f, \"within_bound\": %s},\n",
               ctx.camera_period_ms, ctx.inference_deadline_ms, bound, se.p999,
               n > 0 && se.p999 <= bound ? "true" : "false");
  if (ctx.allocations_counted && ctx.steady.valid && ctx.end.valid) {
    // Growth from the warm-up point when the run reached it, else from the first pose.
    const MemorySample& from = ctx.warm.valid ? ctx.warm : ctx.steady;
    std::fprintf(
        f,
        "  \"memory\": {\"allocations_after_first_pose\": %llu, \"counter_covers_malloc\": "
        "%s, \"rss_kb_after_first_pose\": %llu, \"rss_kb_after_warmup\": %llu, "
        "\"warmup_poses\": %llu, \"rss_kb_end\": %llu, \"rss_growth_kb\": %lld, "
        "\"peak_rss_kb\": %llu%s}\n",
        static_cast<unsigned long long>(ctx.end.allocations - ctx.steady.allocations),
        ctx.counter_covers_malloc ? "true" : "false",
        static_cast<unsigned long long>(ctx.steady.rss_kb),
        static_cast<unsigned long long>(from.rss_kb),
        static_cast<unsigned long long>(ctx.warm.valid ? ctx.warmup_poses : 1),
        static_cast<unsigned long long>(ctx.end.rss_kb),
        static_cast<long long>(ctx.end.rss_kb) - static_cast<long long>(from.rss_kb),
        static_cast<unsigned long long>(ctx.peak_rss_kb), budget_json(ctx.budget).c_str());
  } else {
    std::fprintf(
        f, "  \"memory\": {\"allocations_after_first_pose\": null, \"peak_rss_kb\": %llu%s}\n",
        static_cast<unsigned long long>(ctx.peak_rss_kb), budget_json(ctx.budget).c_str());
  }
  std::fprintf(f, "}\n");
  const bool json_ok = std::fclose(f) == 0;
  if (!json_ok) return Error(Errc::kIo, "timing: error writing %s", json_path);

  std::string csv_path(json_path);
  const size_t dot = csv_path.rfind('.');
  const size_t slash = csv_path.rfind('/');
  if (dot != std::string::npos && (slash == std::string::npos || dot > slash)) csv_path.resize(dot);
  csv_path += ".csv";
  FILE* c = std::fopen(csv_path.c_str(), "w");
  if (!c) {
    return Error(Errc::kIo, "timing: cannot write %s: %s", csv_path.c_str(), std::strerror(errno));
  }
  std::fprintf(c, "index,capture_ns,inference_start_ns,inference_end_ns,publish_ns\n");
  for (size_t i = 0; i < n; ++i) {
    std::fprintf(c, "%zu,%lld,%lld,%lld,%lld\n", i, static_cast<long long>(records[i].capture_ns),
                 static_cast<long long>(records[i].inference_start_ns),
                 static_cast<long long>(records[i].inference_end_ns),
                 static_cast<long long>(records[i].publish_ns));
  }
  if (std::fclose(c) != 0) return Error(Errc::kIo, "timing: error writing %s", csv_path.c_str());
  return ok();
}

}  // namespace aprt
