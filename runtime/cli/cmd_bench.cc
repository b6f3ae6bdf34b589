// aprt bench MODEL [--runs N] [--warmup N] [--json] [--profile] [--seed S]
#include <fcntl.h>
#include <sys/mman.h>
#include <sys/resource.h>
#include <sys/stat.h>
#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <ctime>
#include <random>
#include <vector>

#include "runtime/base/allocation_counter.h"
#include "runtime/cli/args.h"
#include "runtime/cli/commands.h"
#include "runtime/engine/engine.h"
#include "runtime/loop/timing_report.h"

namespace aprt::cli {
namespace {

double now_ms() {
  timespec t{};
  clock_gettime(CLOCK_MONOTONIC, &t);
  return double(t.tv_sec) * 1e3 + double(t.tv_nsec) / 1e6;
}

double percentile(const std::vector<double>& sorted, double p) {
  if (sorted.empty()) return 0.0;
  const double pos = p * double(sorted.size() - 1);
  const size_t lo = size_t(std::floor(pos));
  const size_t hi = std::min(lo + 1, sorted.size() - 1);
  return sorted[lo] + (sorted[hi] - sorted[lo]) * (pos - double(lo));
}

// The model file's pages dropped from the page cache, so the load reads the
// disk as at a cold boot: without root (unlike /proc/sys/vm/drop_caches),
// for this file only. Pages another process has mapped stay; the share left
// is reported. Returns the share of the file's pages still cached, or -1.
double evict_from_page_cache(const char* path) {
  const int fd = open(path, O_RDONLY | O_CLOEXEC);
  if (fd < 0) return -1;
  (void)posix_fadvise(fd, 0, 0, POSIX_FADV_DONTNEED);
  double cached = -1;
  struct stat st {};
  if (fstat(fd, &st) == 0 && st.st_size > 0) {
    const long page = sysconf(_SC_PAGESIZE);
    void* m = mmap(nullptr, size_t(st.st_size), PROT_READ, MAP_SHARED, fd, 0);
    if (m != MAP_FAILED) {
      const size_t pages = (size_t(st.st_size) + size_t(page) - 1) / size_t(page);
      std::vector<unsigned char> in(pages);
      if (mincore(m, size_t(st.st_size), in.data()) == 0) {
        size_t n = 0;
        for (unsigned char c : in) n += c & 1;
        cached = double(n) / double(pages);
      }
      munmap(m, size_t(st.st_size));
    }
  }
  close(fd);
  return cached;
}

long peak_rss_kb() {
  rusage u{};
  getrusage(RUSAGE_SELF, &u);
  return u.ru_maxrss;
}

}  // namespace

int cmd_bench(int argc, char** argv) {
  Args args(argc, argv);
  if (args.flag("--help")) {
    std::printf(
        "usage: aprt bench MODEL [options]\n"
        "  --runs N      timed runs (default 50)\n"
        "  --warmup N    untimed runs first (default 5)\n"
        "  --seed S      seed of the random input (default 1)\n"
        "  --threads N   threads for one frame, including the caller (default 1)\n"
        "  --isa NAME    kernels: auto (default), ref, avx512, avx2, neon\n"
        "  --profile     time every op; print the ops that take the most time\n"
        "  --top N       how many of the slowest ops --profile lists (default 15)\n"
        "  --cold        drop the model file from the page cache first (posix_fadvise; no\n"
        "                root needed): the load as at a cold start\n"
        "  --json        one JSON object on stdout instead of text\n");
    return 0;
  }
  const bool json = args.flag("--json");
  const bool profile = args.flag("--profile");
  const bool cold = args.flag("--cold");
  const long runs = args.integer("--runs", 50, 1, 1000000);
  const long warmup = args.integer("--warmup", 5, 0, 1000000);
  const long seed = args.integer("--seed", 1, 0, 1L << 30);
  const long threads = args.integer("--threads", 1, 1, 16);
  const long top = args.integer("--top", 15, 1, 100000);
  const char* isa = args.value("--isa");
  const char* path = args.positional();
  if (args.refuse("bench")) return 2;
  if (!path) {
    std::fprintf(stderr, "aprt bench: missing MODEL (usage: aprt bench MODEL [options])\n");
    return 2;
  }
  EngineOptions opts;
  opts.threads = int(threads);
  opts.isa = isa;
  // Start-up: the load (read, checks, repacking, the block prefaulted and
  // locked) and the first run after it, as a process's first frame sees them.
  // What the process held before the model (the program and its libraries),
  // so that the load's own peak reads as peak_rss_kb - rss_before_load_kb.
  double cached_share = 1.0;
  if (cold && (cached_share = evict_from_page_cache(path)) < 0) {
    std::fprintf(stderr, "aprt bench: %s: cannot open to drop it from the page cache\n", path);
    return 2;
  }
  const uint64_t rss_before_kb = current_rss_kb();
  const double load_t0 = now_ms();
  auto loaded = Engine::load_file(path, opts);
  const double load_ms = now_ms() - load_t0;
  if (!loaded) {
    std::fprintf(stderr, "aprt bench: %s\n", loaded.error().message());
    return 2;
  }
  Engine& e = *loaded.value();
  std::mt19937 rng(static_cast<uint32_t>(seed));
  std::normal_distribution<float> normal(0.0f, 1.0f);
  Tensor& in = e.input();
  for (size_t i = 0; i < in.numel; ++i) in.f32()[i] = normal(rng);

  std::vector<double> ms(static_cast<size_t>(runs));
  std::vector<uint64_t> op_ns(e.op_count(), 0), op_total(e.op_count(), 0),
      op_min(e.op_count(), UINT64_MAX);
  const double first_t0 = now_ms();
  (void)e.run();
  const double first_ms = now_ms() - first_t0;
  for (long i = 1; i < warmup; ++i) (void)e.run();
  const AllocationScope allocations;
  for (long i = 0; i < runs; ++i) {
    const double t0 = now_ms();
    if (profile) {
      (void)e.run_profiled(op_ns.data());
      for (size_t k = 0; k < op_ns.size(); ++k) {
        op_total[k] += op_ns[k];
        op_min[k] = std::min(op_min[k], op_ns[k]);
      }
    } else {
      (void)e.run();
    }
    ms[size_t(i)] = now_ms() - t0;
  }
  const uint64_t allocs = allocations.count();
  std::vector<double> sorted = ms;
  std::sort(sorted.begin(), sorted.end());
  const double med = percentile(sorted, 0.5), p99 = percentile(sorted, 0.99),
               p999 = percentile(sorted, 0.999);
  const MemoryReport& r = e.memory();
  const double gflops = double(e.total_flops()) / 1e9;
  if (json) {
    std::printf(
        "{\"model\": \"%s\", \"runs\": %ld, \"warmup\": %ld, \"min_ms\": %.4f, \"median_ms\": "
        "%.4f, \"p99_ms\": %.4f, \"p999_ms\": %.4f, \"max_ms\": %.4f, "
        "\"allocations_during_runs\": %llu, "
        "\"allocations_cover_malloc\": %s, \"arena_bytes\": %zu, \"weight_bytes\": %zu, "
        "\"scratch_bytes\": %zu, \"total_bytes\": %zu, \"memory_locked\": %s, "
        "\"peak_rss_kb\": %ld, \"gflop_per_frame\": %.4f, \"gflops\": %.3f, \"threads\": %d, "
        "\"isa\": \"%s\", \"load_ms\": %.3f, \"first_run_ms\": %.3f, "
        "\"load_to_first_result_ms\": %.3f, \"cold\": %s, \"file_cached_share\": %.3f, "
        "\"rss_before_load_kb\": %llu, \"ms\": [",
        path, runs, warmup, sorted.front(), med, p99, p999, sorted.back(),
        static_cast<unsigned long long>(allocs),
        allocation_counter_covers_malloc() ? "true" : "false", r.arena_bytes, r.weight_bytes,
        r.scratch_bytes, r.total_bytes, r.locked ? "true" : "false", peak_rss_kb(), gflops,
        gflops / (med / 1e3), e.threads(), e.isa(), load_ms, first_ms, load_ms + first_ms,
        cold ? "true" : "false", cached_share, static_cast<unsigned long long>(rss_before_kb));
    for (size_t i = 0; i < ms.size(); ++i) std::printf("%s%.4f", i ? ", " : "", ms[i]);
    std::printf("]}\n");
  } else {
    std::printf("model        %s\n", path);
    std::printf("runs         %ld after %ld warm-up, %d thread%s, %s kernels\n", runs, warmup,
                e.threads(), e.threads() > 1 ? "s" : "", e.isa());
    std::printf("start-up     load %.2f ms%s, first run %.3f ms: %.2f ms to the first result\n",
                load_ms, cold ? " (file dropped from the page cache)" : "", first_ms,
                load_ms + first_ms);
    if (cold && cached_share > 0.0)
      std::printf("             %.0f %% of the file stayed cached (mapped by another process)\n",
                  100.0 * cached_share);
    std::printf("latency      min %.3f  median %.3f  p99 %.3f  p99.9 %.3f  max %.3f ms\n",
                sorted.front(), med, p99, p999, sorted.back());
    std::printf("tail         p99 / median %.2f, p99.9 / median %.2f\n", p99 / med, p999 / med);
    std::printf("throughput   %.2f GFLOP/s (%.3f GFLOP per frame)\n", gflops / (med / 1e3), gflops);
    std::printf("allocations  %llu during the timed runs%s\n",
                static_cast<unsigned long long>(allocs),
                allocation_counter_covers_malloc() ? "" : " (operator new only: sanitizer build)");
    std::printf(
        "memory       arena %.3f MB, weights %.2f MB, scratch %.3f MB, total %.2f MB%s; "
        "peak RSS %.1f MB (%.1f MB before the load)\n",
        double(r.arena_bytes) / 1e6, double(r.weight_bytes) / 1e6, double(r.scratch_bytes) / 1e6,
        double(r.total_bytes) / 1e6, r.locked ? " (locked)" : " (not locked: raise ulimit -l)",
        double(peak_rss_kb()) * 1.024 / 1e3, double(rss_before_kb) * 1.024 / 1e3);
  }
  if (profile && !json) {
    std::vector<size_t> order(e.op_count());
    for (size_t i = 0; i < order.size(); ++i) order[i] = i;
    std::sort(order.begin(), order.end(),
              [&](size_t a, size_t b) { return op_total[a] > op_total[b]; });
    uint64_t all = 0;
    for (uint64_t t : op_total) all += t;
    double by_kind[format::kMaxOpCode + 1] = {}, min_kind[format::kMaxOpCode + 1] = {};
    double all_min = 0;
    for (size_t i = 0; i < e.op_count(); ++i) {
      by_kind[int(e.op(i).code)] += double(op_total[i]);
      min_kind[int(e.op(i).code)] += double(op_min[i]);
      all_min += double(op_min[i]);
    }
    // The minimum of each op over the runs is its time without the host's
    // interruptions (a shared machine's noise only ever adds); their sum is
    // what a frame would take if every op ran at its best.
    std::printf("\nper op kind (share of op time; mean and sum of each op's minimum)\n");
    for (int c = 1; c <= format::kMaxOpCode; ++c) {
      if (by_kind[c] > 0) {
        std::printf("  %-18s %5.1f %%  %8.3f ms  min %8.3f ms\n",
                    format::op_name(format::OpCode(c)), 100.0 * by_kind[c] / double(all),
                    by_kind[c] / 1e6 / double(runs), min_kind[c] / 1e6);
      }
    }
    std::printf("  %-18s %5.1f %%  %8.3f ms  min %8.3f ms\n", "all ops", 100.0,
                double(all) / 1e6 / double(runs), all_min / 1e6);
    std::printf("\nslowest ops (mean ms, GFLOP/s at the mean; min ms, GFLOP/s at the min)\n");
    for (size_t k = 0; k < std::min<size_t>(size_t(top), order.size()); ++k) {
      const OpNode& n = e.op(order[k]);
      const double t = double(op_total[order[k]]) / 1e6 / double(runs);
      const double tmin = double(op_min[order[k]]) / 1e6;
      std::printf("  %4zu %-14s %8.3f ms %7.2f  %8.3f ms %7.2f  %-10s %s\n", order[k],
                  format::op_name(n.code), t, t > 0 ? double(n.flops) / 1e6 / t : 0.0, tmin,
                  tmin > 0 ? double(n.flops) / 1e6 / tmin : 0.0, n.kernel, n.name);
    }
  }
  return 0;
}

}  // namespace aprt::cli
