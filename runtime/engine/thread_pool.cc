#include "runtime/engine/thread_pool.h"

#include <linux/futex.h>
#include <sched.h>
#include <sys/syscall.h>
#include <time.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>
#include <new>

#include "runtime/base/check.h"
#include "runtime/engine/denormals.h"

namespace aprt {
namespace {

void cpu_relax() {
#if defined(__x86_64__) || defined(__i386__)
  __builtin_ia32_pause();
#elif defined(__aarch64__)
  asm volatile("yield");
#endif
}

long futex(std::atomic<uint32_t>* word, int op, uint32_t value, const timespec* timeout) {
  return syscall(SYS_futex, reinterpret_cast<uint32_t*>(word), op, value, timeout, nullptr, 0);
}

}  // namespace

Expected<std::unique_ptr<ThreadPool>> ThreadPool::create(int threads, const int* cpus, int n_cpus) {
  APRT_ENSURE(threads >= 1 && threads <= kMaxThreads, Errc::kInvalidArgument,
              "thread pool: %d threads (1..%d)", threads, kMaxThreads);
  std::unique_ptr<ThreadPool> pool(new (std::nothrow) ThreadPool());
  APRT_ENSURE(pool != nullptr, Errc::kOutOfMemory, "thread pool: out of memory");
  for (int i = 0; i < threads - 1; ++i) {
    pool->args_[i] = WorkerArg{pool.get(), i + 1};
    const int rc =
        pthread_create(&pool->handles_[i], nullptr, &ThreadPool::worker_main, &pool->args_[i]);
    if (rc != 0) {
      pool->workers_ = i;  // the destructor joins the ones that started
      return Error(Errc::kOutOfMemory, "thread pool: cannot start worker %d: %s", i + 1,
                   std::strerror(rc));
    }
    pool->workers_ = i + 1;
    if (cpus && i < n_cpus && cpus[i] >= 0) {
      cpu_set_t set;
      CPU_ZERO(&set);
      CPU_SET(cpus[i], &set);
      const int prc = pthread_setaffinity_np(pool->handles_[i], sizeof set, &set);
      APRT_ENSURE(prc == 0, Errc::kInvalidArgument,
                  "thread pool: cannot pin worker %d to CPU %d: %s", i + 1, cpus[i],
                  std::strerror(prc));
    }
  }
  return pool;
}

ThreadPool::~ThreadPool() {
  job_.stop.store(true, std::memory_order_release);
  job_.generation.fetch_add(1, std::memory_order_acq_rel);
  futex(&job_.generation, FUTEX_WAKE_PRIVATE, kMaxThreads, nullptr);
  for (int i = 0; i < workers_; ++i) pthread_join(handles_[i], nullptr);
}

void* ThreadPool::worker_main(void* arg) {
  const DenormalsAreZero ftz;  // workers only ever run inference tasks
  auto* a = static_cast<WorkerArg*>(arg);
  a->pool->worker_loop(a->index);
  return nullptr;
}

namespace {

constexpr uint64_t kGenMask = (uint64_t(1) << 28) - 1;

uint64_t pack(uint32_t generation, int n_tasks, int next) {
  return (uint64_t(generation) & kGenMask) << 36 | uint64_t(n_tasks) << 18 | uint64_t(next);
}

}  // namespace

void ThreadPool::claim_and_run(uint32_t generation, int thread) noexcept {
  const uint64_t gen = uint64_t(generation) & kGenMask;
  uint64_t c = job_.claim.load(std::memory_order_acquire);
  for (;;) {
    if ((c >> 36) != gen) return;  // a later job: this one is done (we were late)
    const int n = int((c >> 18) & kMaxTasksPerJob), next = int(c & kMaxTasksPerJob);
    if (next >= n) return;
    // Read the job before claiming. If the claim succeeds, task `next` was
    // unclaimed, so the job was not complete and the caller had not begun
    // to write the next one: what was read is this job's.
    const TaskFn fn = job_.fn.load(std::memory_order_relaxed);
    void* const ctx = job_.ctx.load(std::memory_order_relaxed);
    if (!job_.claim.compare_exchange_weak(c, c + 1, std::memory_order_acq_rel,
                                          std::memory_order_acquire)) {
      continue;  // c holds the word now
    }
    fn(ctx, next, thread);
    job_.completed.fetch_add(1, std::memory_order_release);
    c = job_.claim.load(std::memory_order_acquire);
  }
}

void ThreadPool::worker_loop(int index) {
  // Generation 0 is the pool's state at creation; a job published before this
  // thread first ran is generation 1 and must not be mistaken for "seen".
  uint32_t seen = 0;
  for (;;) {
    uint32_t g = job_.generation.load(std::memory_order_acquire);
    // Wait for the next job: spin while a frame runs, otherwise sleep with a timeout.
    for (int spins = 0; g == seen; ++spins) {
      if (job_.spinning.load(std::memory_order_relaxed) || spins < 2000) {
        cpu_relax();
      } else {
        job_.sleeping.fetch_add(1, std::memory_order_seq_cst);
        const timespec timeout{0, 100 * 1000 * 1000};
        futex(&job_.generation, FUTEX_WAIT_PRIVATE, seen, &timeout);
        job_.sleeping.fetch_sub(1, std::memory_order_seq_cst);
        spins = 0;
      }
      g = job_.generation.load(std::memory_order_acquire);
    }
    seen = g;
    if (job_.stop.load(std::memory_order_acquire)) return;
    claim_and_run(g, index);
  }
}

void ThreadPool::wake_sleepers() noexcept {
  if (job_.sleeping.load(std::memory_order_seq_cst) > 0) {
    futex(&job_.generation, FUTEX_WAKE_PRIVATE, kMaxThreads, nullptr);
  }
}

void ThreadPool::run(int n_tasks, TaskFn fn, void* ctx) noexcept {
  if (workers_ == 0 || n_tasks <= 1) {
    for (int t = 0; t < n_tasks; ++t) fn(ctx, t, 0);
    return;
  }
  // More tasks than the claim word counts: in jobs of at most that many
  // (no op comes near; the engine's largest has a few thousand).
  for (int first = 0; first < n_tasks; first += kMaxTasksPerJob) {
    if (first == 0 && n_tasks <= kMaxTasksPerJob) {
      run_job(n_tasks, fn, ctx);
      return;
    }
    struct Slice {
      TaskFn fn;
      void* ctx;
      int first;
    } slice{fn, ctx, first};
    const int n = n_tasks - first < kMaxTasksPerJob ? n_tasks - first : kMaxTasksPerJob;
    run_job(
        n,
        [](void* p, int t, int thread) {
          const Slice& s = *static_cast<const Slice*>(p);
          s.fn(s.ctx, s.first + t, thread);
        },
        &slice);
  }
}

void ThreadPool::run_job(int n_tasks, TaskFn fn, void* ctx) noexcept {
  job_.fn.store(fn, std::memory_order_relaxed);
  job_.ctx.store(ctx, std::memory_order_relaxed);
  job_.completed.store(0, std::memory_order_relaxed);
  const uint32_t g = job_.generation.load(std::memory_order_relaxed) + 1;
  job_.claim.store(pack(g, n_tasks, 0), std::memory_order_release);
  job_.generation.store(g, std::memory_order_seq_cst);  // publishes the job
  wake_sleepers();
  claim_and_run(g, 0);
  // Only claimed tasks are waited for: every task is claimed by now (the
  // caller's own loop ended), and a claimant finishes what it took. A
  // claimant preempted in the middle of its task is waited for politely.
  for (int spins = 0; job_.completed.load(std::memory_order_acquire) < n_tasks; ++spins) {
    if (spins < 4000) {
      cpu_relax();
    } else {
      sched_yield();
    }
  }
}

void ThreadPool::frame_begin() noexcept {
  job_.spinning.store(true, std::memory_order_relaxed);
  wake_sleepers();
}

void ThreadPool::frame_end() noexcept {
  job_.spinning.store(false, std::memory_order_relaxed);
}

}  // namespace aprt
