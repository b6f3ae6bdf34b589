// One op of the loaded graph: resolved tensors, prepared state, chosen kernel.
//
// Each op kind has a prepare() (load time: validate shapes and parameters with
// messages, precompute, declare scratch and packed-weight space, pick the eval
// function for the chosen ISA) and an eval() (run time: only reads the
// prepared state and pointers; never allocates, never fails). See
// runtime/engine/ops/.
#pragma once

#include <cstddef>
#include <cstdint>

#include "kernels/gemm/qs8_gemm.h"
#include "kernels/table/kernel_table.h"
#include "runtime/base/expected.h"
#include "runtime/engine/model_file.h"
#include "runtime/engine/tensor.h"
#include "runtime/engine/thread_pool.h"

namespace aprt {

struct RunContext {
  float* scratch = nullptr;  // shared by the op's tasks, sized by OpNode::scratch_floats
  float* thread_scratch[ThreadPool::kMaxThreads] = {};  // OpNode::thread_scratch_floats each
  ThreadPool* pool = nullptr;
  int threads = 1;
};

// fn(data, task, thread) for every task, on the pool if there is one. @rt.
inline void parallel_for(const RunContext& ctx, int n_tasks, ThreadPool::TaskFn fn, void* data) {
  if (ctx.pool && n_tasks > 1) {
    ctx.pool->run(n_tasks, fn, data);
  } else {
    for (int t = 0; t < n_tasks; ++t) fn(data, t, 0);
  }
}

struct OpNode;
using EvalFn = void (*)(const OpNode& node, const RunContext& ctx);

struct OpNode {
  static constexpr size_t kStateBytes = 192;

  int index = 0;
  format::OpCode code = format::OpCode::kAdd;
  const char* name = "";
  const int32_t* params = nullptr;  // kMaxOpParams values from the file
  Tensor* in[format::kMaxOpInputs] = {};
  int n_in = 0;
  Tensor* out[format::kMaxOpOutputs] = {};
  int n_out = 0;
  // Set before prepare(): the chosen ISA's kernels (null: reference kernels)
  // and the thread count the op may split its work for.
  const kernels::KernelSet* ks = nullptr;
  const kernels::QKernelSet* qks = nullptr;  // the int8 kernels that go with ks (null: reference)
  const kernels::Bf16AttentionKernels* bks = nullptr;  // bf16 attention with ks (null: none)
  int threads = 1;
  // Declared by prepare():
  size_t scratch_floats = 0;             // shared by all of the op's tasks
  size_t thread_scratch_floats = 0;      // per thread
  size_t packed_floats = 0;              // weights repacked at load for the kernel
  void (*pack)(OpNode& node) = nullptr;  // fills `packed` once memory exists
  // Bit k: pack() copies input k (a constant) whole into `packed`, with its
  // per-channel scales if it has them, and eval never reads it as stored; a
  // constant every reader packs is not kept after load (one copy of the weights).
  uint32_t packed_inputs = 0;
  // What `packed` holds and its tile (columns per panel; 0: none), for `aprt info`.
  const char* packed_layout = "";
  int packed_tile = 0;
  float* packed = nullptr;
  uint64_t flops = 0;  // multiply-adds x 2, for profiles
  EvalFn eval = nullptr;
  const char* kernel = "ref";  // which implementation eval runs, for `aprt info`
  alignas(16) unsigned char state[kStateBytes] = {};

  template <class S>
  S& state_as() {
    static_assert(sizeof(S) <= kStateBytes, "op state too large");
    return *reinterpret_cast<S*>(state);
  }
  template <class S>
  const S& state_as() const {
    static_assert(sizeof(S) <= kStateBytes, "op state too large");
    return *reinterpret_cast<const S*>(state);
  }
};

struct OpKind {
  const char* name;
  int min_inputs;
  int max_inputs;
  Status (*prepare)(OpNode& node);
};

// The op kind for `code`, or null.
const OpKind* find_op_kind(format::OpCode code);

// Splits `count` items into at most `max_tasks` contiguous ranges of whole
// `unit`s; task t covers [begin, end). Used by ops to size their parallel work.
struct Split {
  int count = 0, unit = 1, per_task = 1, tasks = 1;
  int begin(int t) const { return t * per_task; }
  int end(int t) const { return (t + 1) * per_task < count ? (t + 1) * per_task : count; }
};
inline Split make_split(int count, int unit, int max_tasks) {
  Split s;
  s.count = count;
  s.unit = unit < 1 ? 1 : unit;
  if (max_tasks < 1) max_tasks = 1;
  const int units = (count + s.unit - 1) / s.unit;
  const int units_per_task = units <= max_tasks ? 1 : (units + max_tasks - 1) / max_tasks;
  s.per_task = units_per_task * s.unit;
  s.tasks = count <= 0 ? 0 : (count + s.per_task - 1) / s.per_task;
  return s;
}

}  // namespace aprt
