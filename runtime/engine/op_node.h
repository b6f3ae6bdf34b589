// One op of the loaded graph: resolved tensors, prepared state, chosen kernel.
//
// Each op kind has a prepare() (load time: validate shapes and parameters with
// messages, precompute, declare scratch, pick the eval function) and an eval()
// (run time: only reads the prepared state and pointers; never allocates,
// never fails). See runtime/engine/ops/.
#pragma once

#include <cstddef>
#include <cstdint>

#include "runtime/common/expected.h"
#include "runtime/engine/model_file.h"
#include "runtime/engine/tensor.h"

namespace aprt {

struct RunContext {
  float* scratch = nullptr;  // the op's scratch, sized by prepare()
};

struct OpNode;
using EvalFn = void (*)(const OpNode& node, const RunContext& ctx);

struct OpNode {
  static constexpr size_t kStateBytes = 128;

  int index = 0;
  format::OpCode code = format::OpCode::kAdd;
  const char* name = "";
  const int32_t* params = nullptr;  // kMaxOpParams values from the file
  Tensor* in[format::kMaxOpInputs] = {};
  int n_in = 0;
  Tensor* out[format::kMaxOpOutputs] = {};
  int n_out = 0;
  size_t scratch_floats = 0;
  uint64_t flops = 0;  // multiply-adds x 2, for profiles
  EvalFn eval = nullptr;
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

}  // namespace aprt
