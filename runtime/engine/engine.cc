#include "runtime/engine/engine.h"

#include <fcntl.h>
#include <sys/mman.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cerrno>
#include <cstdint>
#include <cstdlib>
#include <cstring>
#include <ctime>
#include <new>

#include "kernels/table/cpu_features.h"
#include "runtime/base/check.h"
#include "runtime/base/file_io.h"
#include "runtime/engine/denormals.h"
#include "runtime/engine/memory_planner.h"

namespace aprt {
namespace {

constexpr size_t kAlign = 64;
constexpr size_t kNotInArena = SIZE_MAX;
constexpr uint64_t kMaxModelFileBytes = uint64_t(4) << 30;

size_t round_up(size_t n, size_t a) {
  return (n + a - 1) / a * a;
}

bool in_arena(const Tensor& t) {
  return t.kind != format::TensorKind::kConst;
}

// The engine's one region: anonymous, 2 MiB-aligned and advised for
// transparent huge pages (the region is prefaulted at load, so the kernel
// finds the huge pages then, never during run()). The full 224 model
// touches ~100 MB per frame; on 4 KiB pages that is ~25 000 TLB entries
// refilled every frame; huge pages measured ~0.5 % faster on it. With THP
// off the advice is ignored. nullptr (errno set) if mmap fails.
uint8_t* map_region(size_t bytes) {
  constexpr size_t kHuge = size_t(2) << 20;
  const size_t span = bytes + kHuge;
  void* p = mmap(nullptr, span, PROT_READ | PROT_WRITE, MAP_PRIVATE | MAP_ANONYMOUS, -1, 0);
  if (p == MAP_FAILED) return nullptr;
  const uintptr_t base = reinterpret_cast<uintptr_t>(p);
  const uintptr_t aligned = (base + kHuge - 1) & ~uintptr_t(kHuge - 1);
  if (aligned > base) munmap(p, aligned - base);
  const uintptr_t end = aligned + bytes, span_end = base + span;
  if (span_end > end) munmap(reinterpret_cast<void*>(end), span_end - end);
#ifdef MADV_HUGEPAGE
  (void)madvise(reinterpret_cast<void*>(aligned), bytes, MADV_HUGEPAGE);
#endif
  return reinterpret_cast<uint8_t*>(aligned);
}

}  // namespace

Engine::~Engine() {
  if (region_ && region_owned_) {
    if (memory_.locked) munlock(region_, region_bytes_);
    munmap(region_, region_bytes_);
  }
}

Status Engine::bind(const uint8_t* data, size_t size) {
  auto parsed = ModelFile::parse(data, size, ParseOptions{.verify_checksums = false});
  if (!parsed) return parsed.error();
  model_ = std::move(parsed.value());
  const auto& entries = model_.tensors();
  tensors_.assign(entries.size(), Tensor{});
  for (size_t i = 0; i < entries.size(); ++i) {
    const TensorEntry& e = entries[i];
    Tensor& t = tensors_[i];
    t.name = e.name;
    t.dtype = e.dtype;
    t.kind = e.kind;
    t.rank = e.rank;
    for (int d = 0; d < e.rank; ++d) t.dims[d] = int(e.dims[d]);
    t.numel = e.numel;
    t.bytes = e.bytes;
    t.scale = e.scale;
    t.zero_point = e.zero_point;
    if (t.is_const()) t.data = const_cast<uint8_t*>(model_.weights() + e.data_offset);
  }
  for (size_t i = 0; i < entries.size(); ++i) {
    if (entries[i].qscale_tensor >= 0) tensors_[i].qscale = &tensors_[entries[i].qscale_tensor];
  }
  input_ = &tensors_[model_.input_index()];
  output_ = &tensors_[model_.output_index()];
  const auto& ops = model_.ops();
  nodes_.assign(ops.size(), OpNode{});
  for (size_t i = 0; i < ops.size(); ++i) {
    const OpEntry& o = ops[i];
    OpNode& n = nodes_[i];
    n.index = int(i);
    n.code = o.code;
    n.name = o.name;
    n.params = o.params;
    n.n_in = o.n_in;
    n.n_out = o.n_out;
    for (int k = 0; k < o.n_in; ++k) n.in[k] = o.in[k] >= 0 ? &tensors_[o.in[k]] : nullptr;
    for (int k = 0; k < o.n_out; ++k) n.out[k] = &tensors_[o.out[k]];
  }
  return ok();
}

Status Engine::prepare_ops() {
  for (OpNode& n : nodes_) {
    const OpKind* kind = find_op_kind(n.code);
    APRT_ENSURE(kind != nullptr, Errc::kBadOp, "model_bin: op %d '%s': opcode %u not supported",
                n.index, n.name, unsigned(n.code));
    APRT_ENSURE(n.n_in >= kind->min_inputs && n.n_in <= kind->max_inputs, Errc::kBadOp,
                "model_bin: op %d '%s' (%s) has %d inputs (%d..%d expected)", n.index, n.name,
                kind->name, n.n_in, kind->min_inputs, kind->max_inputs);
    APRT_ENSURE(n.n_out == 1, Errc::kBadOp, "model_bin: op %d '%s' (%s) has %d outputs", n.index,
                n.name, kind->name, n.n_out);
    if (Status s = kind->prepare(n); !s) return s;
    APRT_ENSURE(n.eval != nullptr, Errc::kUnsupported,
                "model_bin: op %d '%s' (%s): no kernel for this configuration", n.index, n.name,
                kind->name);
  }
  return ok();
}

void Engine::plan(size_t* arena_bytes) {
  const int n_ops = int(nodes_.size());
  std::vector<PlanBuffer> buffers;
  std::vector<int> owner;
  std::vector<int> slot(tensors_.size(), -1);
  for (size_t i = 0; i < tensors_.size(); ++i) {
    if (!in_arena(tensors_[i])) continue;
    slot[i] = int(buffers.size());
    const bool is_input = tensors_[i].kind == format::TensorKind::kInput;
    // Activations start "unwritten" (first = n_ops, last = -1) until an op writes them.
    buffers.push_back(PlanBuffer{tensors_[i].bytes, is_input ? -1 : n_ops, -1, 0});
    owner.push_back(int(i));
  }
  for (int k = 0; k < n_ops; ++k) {
    const OpNode& n = nodes_[k];
    for (int j = 0; j < n.n_out; ++j) {
      PlanBuffer& b = buffers[slot[n.out[j] - tensors_.data()]];
      b.first = k;
      b.last = std::max(b.last, k);
    }
    for (int j = 0; j < n.n_in; ++j) {
      if (!n.in[j] || !in_arena(*n.in[j])) continue;
      PlanBuffer& b = buffers[slot[n.in[j] - tensors_.data()]];
      b.last = std::max(b.last, k);
    }
  }
  buffers[slot[output_ - tensors_.data()]].last = n_ops;  // read after run()
  const PlanSummary s = plan_greedy_by_size(buffers.data(), int(buffers.size()), kAlign);
  arena_offsets_.assign(tensors_.size(), kNotInArena);
  for (size_t b = 0; b < buffers.size(); ++b) arena_offsets_[owner[b]] = buffers[b].offset;
  *arena_bytes = s.arena_bytes;
  memory_.arena_bytes = s.arena_bytes;
  memory_.arena_sum_bytes = s.sum_bytes;
  memory_.arena_lower_bound_bytes = s.lower_bound_bytes;
}

Expected<std::unique_ptr<Engine>> Engine::build(const uint8_t* data, size_t size,
                                                const EngineOptions& options, bool plan_only,
                                                size_t* required) {
  std::unique_ptr<Engine> e(new (std::nothrow) Engine());
  APRT_ENSURE(e != nullptr, Errc::kOutOfMemory, "engine: out of memory");
  APRT_ENSURE(options.threads >= 1 && options.threads <= ThreadPool::kMaxThreads,
              Errc::kInvalidArgument, "engine: %d threads (1..%d)", options.threads,
              ThreadPool::kMaxThreads);
  auto table = kernels::pick_kernels(options.isa ? options.isa : std::getenv("APRT_ISA"));
  if (!table) return table.error();
  e->kt_ = table.value();
  if (Status s = e->bind(data, size); !s) return s.error();
  if (options.expect_modality != 0) {
    const auto m = uint32_t(e->model_.meta().modality);
    APRT_ENSURE(m == options.expect_modality, Errc::kWrongTarget,
                "model_bin: model is for modality '%s', this runtime is configured for '%s'",
                format::modality_name(e->model_.meta().modality),
                format::modality_name(format::Modality(options.expect_modality)));
  }
  for (OpNode& n : e->nodes_) {
    n.ks = e->kt_.f32;
    n.qks = e->kt_.qs8;
    n.bks = e->kt_.bf16;
    n.threads = options.threads;
  }
  if (Status s = e->prepare_ops(); !s) return s.error();
  size_t arena = 0;
  e->plan(&arena);
  MemoryReport& m = e->memory_;
  m.packed_bytes = 0;
  for (const OpNode& n : e->nodes_) {
    e->scratch_floats_ = std::max(e->scratch_floats_, n.scratch_floats);
    e->thread_scratch_floats_ = std::max(e->thread_scratch_floats_, n.thread_scratch_floats);
    m.packed_bytes += round_up(n.packed_floats * sizeof(float), kAlign);
  }
  m.image_bytes = round_up(size, kAlign);
  m.weight_bytes = 0;
  for (const Tensor& t : e->tensors_) m.weight_bytes += t.is_const() ? t.bytes : 0;
  m.scratch_bytes =
      round_up(e->scratch_floats_ * sizeof(float), kAlign) +
      size_t(options.threads) * round_up(e->thread_scratch_floats_ * sizeof(float), kAlign);
  m.total_bytes = m.image_bytes + m.packed_bytes + round_up(arena, kAlign) + m.scratch_bytes;
  if (required) *required = m.total_bytes;
  (void)plan_only;  // both passes plan; only the caller decides what to keep
  return e;
}

Expected<size_t> Engine::memory_required(const uint8_t* data, size_t size) {
  // Validate with checksums, then plan.
  auto checked = ModelFile::parse(data, size);
  if (!checked) return checked.error();
  size_t required = 0;
  auto e = build(data, size, EngineOptions{}, true, &required);
  if (!e) return e.error();
  return required;
}

Expected<std::unique_ptr<Engine>> Engine::load_memory(const uint8_t* data, size_t size,
                                                      const EngineOptions& options) {
  if (const char* missing = kernels::missing_build_feature())
    return Error(Errc::kUnsupported,
                 "engine: this build assumes %s (compiled with -march=...), which this CPU does "
                 "not report; rebuild for the target's baseline (docs/architecture.md)",
                 missing);
  // Pass 1 on the caller's bytes: validate everything (checksums included) and size.
  auto checked =
      ModelFile::parse(data, size, ParseOptions{.verify_checksums = options.verify_checksums});
  if (!checked) return checked.error();
  size_t required = 0;
  {
    auto probe = build(data, size, options, true, &required);
    if (!probe) return probe.error();
  }
  // Take the memory once.
  uint8_t* region = nullptr;
  bool owned = false;
  if (options.memory) {
    APRT_ENSURE(reinterpret_cast<uintptr_t>(options.memory) % kAlign == 0, Errc::kInvalidArgument,
                "engine: caller memory must be %zu-byte aligned", kAlign);
    APRT_ENSURE(options.memory_bytes >= required, Errc::kInvalidArgument,
                "engine: caller memory has %zu bytes, the model needs %zu", options.memory_bytes,
                required);
    region = static_cast<uint8_t*>(options.memory);
  } else {
    region = map_region(required);
    APRT_ENSURE(region != nullptr, Errc::kOutOfMemory, "engine: cannot map %zu bytes: %s", required,
                std::strerror(errno));
    owned = true;
  }
  std::memcpy(region, data, size);
  // Pass 2 on the copy the engine keeps (identical bytes; no second checksum pass).
  auto built = build(region, size, options, false, nullptr);
  if (!built) {
    if (owned) munmap(region, required);
    return built.error();
  }
  std::unique_ptr<Engine> e = std::move(built.value());
  e->region_ = region;
  e->region_bytes_ = required;
  e->region_owned_ = owned;
  MemoryReport& m = e->memory_;
  m.caller_memory = !owned;
  // Bind: packed weights, then the arena, then the scratch areas.
  uint8_t* cursor = region + m.image_bytes;
  for (OpNode& n : e->nodes_) {
    if (!n.packed_floats) continue;
    n.packed = reinterpret_cast<float*>(cursor);
    cursor += round_up(n.packed_floats * sizeof(float), kAlign);
  }
  uint8_t* arena = cursor;
  for (size_t i = 0; i < e->tensors_.size(); ++i) {
    if (e->arena_offsets_[i] != kNotInArena) e->tensors_[i].data = arena + e->arena_offsets_[i];
  }
  cursor = arena + round_up(m.arena_bytes, kAlign);
  // Prefault: every page after the image is written once here, not during run().
  std::memset(region + m.image_bytes, 0, required - m.image_bytes);
  e->ctx_.scratch = reinterpret_cast<float*>(cursor);
  cursor += round_up(e->scratch_floats_ * sizeof(float), kAlign);
  for (int t = 0; t < options.threads; ++t) {
    e->ctx_.thread_scratch[t] = reinterpret_cast<float*>(cursor);
    cursor += round_up(e->thread_scratch_floats_ * sizeof(float), kAlign);
  }
  for (OpNode& n : e->nodes_) {
    if (n.pack) n.pack(n);
  }
  if (options.threads > 1) {
    auto pool = ThreadPool::create(options.threads, options.cpus, options.n_cpus);
    if (!pool) {
      e.reset();
      if (owned) munmap(region, required);
      return pool.error();
    }
    e->pool_ = std::move(pool.value());
    e->ctx_.pool = e->pool_.get();
    e->ctx_.threads = options.threads;
  }
  if (options.lock_memory) {
    if (mlock(region, required) == 0) {
      m.locked = true;
    } else {
      m.lock_errno = errno;
      APRT_ENSURE(!options.require_locked, Errc::kOutOfMemory,
                  "engine: cannot lock %zu bytes in RAM (%s); raise RLIMIT_MEMLOCK (ulimit -l) "
                  "or grant CAP_IPC_LOCK",
                  required, std::strerror(errno));
    }
  }
  return e;
}

Expected<std::vector<uint8_t>> Engine::read_model_file(const char* path) {
  // Never blocks on what is not a file (a FIFO, a device: refused at open),
  // and reads the header before the body: a large file that is no model, or
  // whose header disagrees with its size, is refused after 64 bytes.
  auto f = open_input_file(path, kMaxModelFileBytes, "model_bin");
  if (!f) return f.error();
  const uint64_t size = f->size();
  uint8_t head[format::kHeaderBytes];
  const long got_head = f->read(head, size < sizeof head ? size_t(size) : sizeof head);
  APRT_ENSURE(got_head >= 0, Errc::kIo, "model_bin: cannot read '%s': %s", path,
              std::strerror(errno));
  APRT_ENSURE(uint64_t(got_head) == size || got_head == long(sizeof head), Errc::kIo,
              "model_bin: short read on '%s'", path);
  APRT_ENSURE(size >= 8 && std::memcmp(head, format::kMagic, 8) == 0, Errc::kBadMagic,
              "model_bin: '%s' is not an aprt model file (bad magic)", path);
  if (size >= sizeof head) {
    uint64_t declared = 0;
    std::memcpy(&declared, head + 16, 8);
    APRT_ENSURE(declared == size, declared > size ? Errc::kTruncated : Errc::kBadHeader,
                "model_bin: '%s': header says %llu bytes, file has %llu (%s)", path,
                static_cast<unsigned long long>(declared), static_cast<unsigned long long>(size),
                declared > size ? "file truncated?" : "trailing data?");
  }
  std::vector<uint8_t> bytes;
  bytes.resize(size_t(size));
  std::memcpy(bytes.data(), head, size_t(got_head));
  const long rest = f->read(bytes.data() + got_head, bytes.size() - size_t(got_head));
  APRT_ENSURE(rest >= 0 && uint64_t(got_head) + uint64_t(rest) == size, Errc::kIo,
              "model_bin: short read on '%s' (%lld of %llu bytes; changed while read?)", path,
              static_cast<long long>(got_head + (rest > 0 ? rest : 0)),
              static_cast<unsigned long long>(size));
  return bytes;
}

Expected<std::unique_ptr<Engine>> Engine::load_file(const char* path,
                                                    const EngineOptions& options) {
  auto bytes = read_model_file(path);
  if (!bytes) return bytes.error();
  auto e = load_memory(bytes->data(), bytes->size(), options);
  if (!e) {
    Error err = e.error();
    err.with_context("%s", path);
    return err;
  }
  return e;
}

Status Engine::run() noexcept {
  const DenormalsAreZero ftz;
  if (pool_) pool_->frame_begin();
  for (const OpNode& n : nodes_) n.eval(n, ctx_);
  if (pool_) pool_->frame_end();
  return ok();
}

Status Engine::run_profiled(uint64_t* op_nanos) noexcept {
  const DenormalsAreZero ftz;
  if (pool_) pool_->frame_begin();
  for (size_t i = 0; i < nodes_.size(); ++i) {
    timespec a{}, b{};
    clock_gettime(CLOCK_MONOTONIC, &a);
    nodes_[i].eval(nodes_[i], ctx_);
    clock_gettime(CLOCK_MONOTONIC, &b);
    op_nanos[i] = uint64_t(b.tv_sec - a.tv_sec) * 1000000000ull + uint64_t(b.tv_nsec - a.tv_nsec);
  }
  if (pool_) pool_->frame_end();
  return ok();
}

const char* Engine::isa() const {
  return kt_.name();
}

uint64_t Engine::total_flops() const {
  uint64_t f = 0;
  for (const OpNode& n : nodes_) f += n.flops;
  return f;
}

}  // namespace aprt
