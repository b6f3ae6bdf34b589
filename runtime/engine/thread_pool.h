// A fixed pool of worker threads for splitting one op across cores.
//
// Created at Engine::load() (optionally pinned); nothing is created or freed
// afterwards. The calling thread takes part as thread 0. Between
// run_frame_begin() and run_frame_end() the workers spin on an atomic
// generation counter, so starting an op costs no system call; outside a frame
// they sleep on a futex with a timeout. Tasks are claimed from one atomic
// word (the job's generation, task count and next task): a task's result
// never depends on which thread ran it, so results are identical for any
// thread count.
//
// The caller waits only for tasks that were claimed, never for a worker to
// show up: a worker the scheduler has preempted (another process on its
// core) simply finds the job done when it runs again, and the caller has
// taken its share. (It waited for every worker to acknowledge each job
// before: one preempted worker stalled the frame for a scheduler time slice,
// which is what made two threads' p99 four times their median.)
#pragma once

#include <pthread.h>

#include <atomic>
#include <cstdint>
#include <memory>

#include "runtime/base/expected.h"

namespace aprt {

class ThreadPool {
 public:
  static constexpr int kMaxThreads = 16;
  using TaskFn = void (*)(void* ctx, int task, int thread);

  // `threads` in 1..kMaxThreads including the caller; `cpus` (may be null)
  // lists a CPU per worker (cpus[i] pins worker i+1; the caller is not pinned).
  static Expected<std::unique_ptr<ThreadPool>> create(int threads, const int* cpus, int n_cpus);
  ~ThreadPool();
  ThreadPool(const ThreadPool&) = delete;
  ThreadPool& operator=(const ThreadPool&) = delete;

  int threads() const { return workers_ + 1; }

  // Runs fn(ctx, task, thread) for every task in [0, n_tasks) and returns when
  // all are done. @rt: no allocation; waits only for tasks already claimed.
  void run(int n_tasks, TaskFn fn, void* ctx) noexcept;

  // Workers spin (no futex) between these two calls.
  void frame_begin() noexcept;
  void frame_end() noexcept;

 private:
  ThreadPool() = default;
  static void* worker_main(void* arg);
  void worker_loop(int index);
  void wake_sleepers() noexcept;

  // The claim word: generation (28 bits) | task count (18) | next task (18).
  static constexpr int kTaskBits = 18;
  static constexpr int kMaxTasksPerJob = (1 << kTaskBits) - 1;
  // Claims and runs tasks of job `generation` until none is left or the job
  // is no longer current; `thread` is the claimant's index.
  void claim_and_run(uint32_t generation, int thread) noexcept;
  void run_job(int n_tasks, TaskFn fn, void* ctx) noexcept;

  struct alignas(64) Job {
    std::atomic<uint32_t> generation{0};  // futex word: bumped per job
    std::atomic<uint64_t> claim{0};
    std::atomic<int> completed{0};  // tasks of the current job finished
    std::atomic<int> sleeping{0};
    std::atomic<bool> spinning{false};
    std::atomic<bool> stop{false};
    // The job, written by the caller before the claim word; read by a
    // claimant before its claim succeeds (a successful claim proves them
    // current: see claim_and_run).
    std::atomic<TaskFn> fn{nullptr};
    std::atomic<void*> ctx{nullptr};
  };
  Job job_;
  int workers_ = 0;
  pthread_t handles_[kMaxThreads] = {};
  struct WorkerArg {
    ThreadPool* pool;
    int index;
  };
  WorkerArg args_[kMaxThreads] = {};
};

}  // namespace aprt
