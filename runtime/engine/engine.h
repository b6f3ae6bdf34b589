// The inference engine: load -> validate -> plan -> run.
//
// Engine::load() reads and validates a model_bin file, prepares every op,
// plans the activation arena from tensor lifetimes and then takes all the
// memory it will ever use in one piece (or uses the caller's buffer):
//
//   [ tables | kept weights | packed weights | activation arena | scratch ]
//
// One copy of the weights: each constant is either kept as stored (read by
// run() as it is in the file: biases, norms, depthwise filters) or packed at
// load into the layout its kernel reads, and then not kept. The tables are the
// file without its WEIGHTS section (names, metadata). The caller's bytes (or
// the file) are not referenced after load() returns.
//
// It prefaults and (best effort, or required) locks that memory. After load()
// returns, run() allocates nothing, takes no locks and does a fixed amount of
// work; its only system call is a futex wake of sleeping workers when
// threads > 1. Results are bit-for-bit identical for every thread count.
//
// Thread safety: one Engine runs one frame at a time; input()/output() belong to
// the thread calling run().
#pragma once

#include <cstddef>
#include <cstdint>
#include <memory>
#include <vector>

#include "runtime/base/expected.h"
#include "runtime/engine/model_file.h"
#include "runtime/engine/op_node.h"
#include "runtime/engine/tensor.h"
#include "runtime/engine/thread_pool.h"

namespace aprt {

struct EngineOptions {
  // Caller-owned memory for everything (64-byte aligned, at least
  // Engine::memory_required() bytes); null to let load() map its own.
  void* memory = nullptr;
  size_t memory_bytes = 0;
  bool lock_memory = true;      // mlock the working memory (best effort)
  bool require_locked = false;  // fail load() if mlock is refused
  // If non-zero, refuse models of another modality (Errc::kWrongTarget).
  uint32_t expect_modality = 0;
  // Section checksums are always verified on vehicles; fuzzers turn this off to
  // reach the checks behind them.
  bool verify_checksums = true;
  // Kernels: null = $APRT_ISA, else auto; or "auto", "ref", "avx512", "avx2", "neon".
  const char* isa = nullptr;
  // Threads for one run(), including the caller (1..16). Workers are created
  // at load and pinned to cpus[0..n_cpus) if given.
  int threads = 1;
  const int* cpus = nullptr;
  int n_cpus = 0;
};

struct MemoryReport {
  size_t file_bytes = 0;    // the model file
  size_t weight_bytes = 0;  // constant tensors in the file
  size_t tables_bytes = 0;  // the file without its weights (names, metadata)
  size_t kept_bytes = 0;    // constants run() reads as stored
  size_t kept_count = 0;
  size_t packed_bytes = 0;             // weights repacked for the kernels at load
  size_t packed_count = 0;             // ops with packed weights
  size_t arena_bytes = 0;              // activation arena as planned
  size_t arena_sum_bytes = 0;          // sum of all activation tensors (no reuse)
  size_t arena_lower_bound_bytes = 0;  // largest set of simultaneously live tensors
  size_t scratch_bytes = 0;
  size_t total_bytes = 0;
  bool caller_memory = false;
  bool locked = false;
  int lock_errno = 0;
};

class Engine {
 public:
  static Expected<std::unique_ptr<Engine>> load_file(const char* path,
                                                     const EngineOptions& options = {});
  static Expected<std::unique_ptr<Engine>> load_memory(const uint8_t* data, size_t size,
                                                       const EngineOptions& options = {});
  // A model file's bytes (size-checked, fully read), for callers that check
  // them (a signature) before load_memory(). load_file() never holds the
  // whole file: it reads the weights piece by piece into their place, so the
  // process's peak is the engine's block and its largest packed tensor.
  static Expected<std::vector<uint8_t>> read_model_file(const char* path);
  // Bytes load_memory() needs for EngineOptions::memory.
  static Expected<size_t> memory_required(const uint8_t* data, size_t size);

  ~Engine();
  Engine(const Engine&) = delete;
  Engine& operator=(const Engine&) = delete;

  // The input tensor: NHWC f32 [1, H, W, C], normalised as the metadata says.
  Tensor& input() { return *input_; }
  // The raw output: x y z (min-max normalised) qw qx qy qz (not normalised).
  const Tensor& output() const { return *output_; }

  // @rt: bounded by the model; no allocation, no locks, no system calls.
  Status run() noexcept;
  // As run(), recording each op's duration in nanoseconds into op_nanos[op_count()].
  Status run_profiled(uint64_t* op_nanos) noexcept;

  const ModelMeta& meta() const { return model_.meta(); }
  const ModelFile& model() const { return model_; }
  const MemoryReport& memory() const { return memory_; }
  const void* memory_block() const { return region_; }  // MemoryReport::total_bytes long
  const char* isa() const;  // the kernels chosen at load ("avx512", "ref", ...)
  // Those kernels (null: the reference kernels), e.g. for the frame
  // preprocessing that feeds this engine.
  const kernels::KernelSet* kernel_set() const { return kt_.f32; }
  const kernels::KernelTable& kernel_table() const { return kt_; }
  int threads() const { return pool_ ? pool_->threads() : 1; }
  size_t op_count() const { return nodes_.size(); }
  const OpNode& op(size_t i) const { return nodes_[i]; }
  size_t tensor_count() const { return tensors_.size(); }
  const Tensor& tensor(size_t i) const { return tensors_[i]; }
  uint64_t total_flops() const;

 private:
  Engine() = default;
  // Where load() reads the model: `data` holds all of it (in memory), or,
  // with fd >= 0, only its tables, in place in a reservation the size of the
  // file: the weights are read from the file into where they go (kept, or a
  // buffer to pack from), never all at once.
  struct Source {
    const uint8_t* data = nullptr;
    size_t size = 0;
    int fd = -1;
    bool read(uint64_t offset, size_t n, void* dst) const;
  };
  // ParseOptions::section_crc and ::fetch over a Source with a file.
  static bool crc_from_file(void* source, uint64_t offset, uint64_t size, uint32_t* crc);
  static bool fetch_from_file(void* source, uint64_t offset, uint64_t size);
  static Expected<std::unique_ptr<Engine>> load_image(const Source& source,
                                                      const EngineOptions& options);
  static Expected<std::unique_ptr<Engine>> build(const uint8_t* data, size_t size,
                                                 const EngineOptions& options, bool plan_only,
                                                 size_t* required);
  Status place_constants(uint8_t* tables, uint8_t* kept, const Source& source, uint8_t* spare,
                         size_t spare_bytes);
  Status bind(const uint8_t* data, size_t size);
  Status prepare_ops();
  void plan(size_t* arena_bytes);
  void mark_kept();

  ModelFile model_;
  std::vector<Tensor> tensors_;
  std::vector<OpNode> nodes_;
  std::vector<size_t> arena_offsets_;  // per tensor; SIZE_MAX if not in the arena
  std::vector<uint8_t> kept_;          // per tensor: a constant run() reads as stored
  Tensor* input_ = nullptr;
  Tensor* output_ = nullptr;
  uint8_t* region_ = nullptr;  // tables | kept | packed | arena | scratch
  size_t region_bytes_ = 0;
  bool region_owned_ = false;
  kernels::KernelTable kt_;  // the ISA chosen at load (kernels/table/kernel_table.h)
  std::unique_ptr<ThreadPool> pool_;
  RunContext ctx_;
  size_t scratch_floats_ = 0;         // shared, max over ops
  size_t thread_scratch_floats_ = 0;  // per thread, max over ops
  MemoryReport memory_;
};

}  // namespace aprt
