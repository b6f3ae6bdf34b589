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
#include "runtime/base/crc32.h"
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
  e->mark_kept();
  MemoryReport& m = e->memory_;
  m.packed_bytes = 0;
  for (const OpNode& n : e->nodes_) {
    e->scratch_floats_ = std::max(e->scratch_floats_, n.scratch_floats);
    e->thread_scratch_floats_ = std::max(e->thread_scratch_floats_, n.thread_scratch_floats);
    m.packed_bytes += round_up(n.packed_floats * sizeof(float), kAlign);
    m.packed_count += n.packed_floats ? 1 : 0;
  }
  m.file_bytes = size;
  m.tables_bytes = round_up(size_t(e->model_.tables_bytes()), kAlign);
  m.weight_bytes = 0;
  m.kept_bytes = 0;
  for (size_t i = 0; i < e->tensors_.size(); ++i) {
    const Tensor& t = e->tensors_[i];
    m.weight_bytes += t.is_const() ? t.bytes : 0;
    m.kept_bytes += e->kept_[i] ? round_up(t.bytes, kAlign) : 0;
    m.kept_count += e->kept_[i];
  }
  m.scratch_bytes =
      round_up(e->scratch_floats_ * sizeof(float), kAlign) +
      size_t(options.threads) * round_up(e->thread_scratch_floats_ * sizeof(float), kAlign);
  m.total_bytes =
      m.tables_bytes + m.kept_bytes + m.packed_bytes + round_up(arena, kAlign) + m.scratch_bytes;
  if (required) *required = m.total_bytes;
  (void)plan_only;  // both passes plan; only the caller decides what to keep
  return e;
}

// A constant is kept unless every op that reads it packs it (OpNode::packed_inputs);
// per-channel scales go with the weights they scale.
void Engine::mark_kept() {
  kept_.assign(tensors_.size(), 0);
  for (const OpNode& n : nodes_) {
    for (int k = 0; k < n.n_in; ++k) {
      const Tensor* t = n.in[k];
      if (t && t->is_const() && !(n.packed_inputs & (1u << k)))
        kept_[size_t(t - tensors_.data())] = 1;
    }
  }
  for (size_t i = 0; i < tensors_.size(); ++i) {
    if (kept_[i] && tensors_[i].qscale) kept_[size_t(tensors_[i].qscale - tensors_.data())] = 1;
  }
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
  return load_image(Source{data, size, -1}, options);
}

bool Engine::Source::read(uint64_t offset, size_t n, void* dst) const {
  if (offset > size || n > size - offset) return false;
  if (fd < 0) {
    std::memcpy(dst, data + offset, n);
    return true;
  }
  auto* out = static_cast<uint8_t*>(dst);
  while (n > 0) {
    const ssize_t got = pread(fd, out, n, off_t(offset));
    if (got < 0 && errno == EINTR) continue;
    if (got <= 0) return false;
    out += got;
    offset += uint64_t(got);
    n -= size_t(got);
  }
  return true;
}

// Bytes of the file into their place in the source's reservation.
bool Engine::fetch_from_file(void* context, uint64_t offset, uint64_t size) {
  const auto* source = static_cast<const Source*>(context);
  return source->read(offset, size_t(size), const_cast<uint8_t*>(source->data) + offset);
}

// A section's checksum read from the file through a 1 MiB buffer, mapped
// for the call and unmapped after it: from malloc, a buffer this size stays
// in the heap once glibc's mmap threshold has risen past it, resident for
// the life of the process.
bool Engine::crc_from_file(void* context, uint64_t offset, uint64_t size, uint32_t* crc) {
  const auto* source = static_cast<const Source*>(context);
  constexpr size_t kPiece = size_t(1) << 20;
  void* map = mmap(nullptr, kPiece, PROT_READ | PROT_WRITE, MAP_PRIVATE | MAP_ANONYMOUS, -1, 0);
  if (map == MAP_FAILED) return false;
  auto* buf = static_cast<uint8_t*>(map);
  uint32_t c = 0;
  bool ok = true;
  for (uint64_t at = 0; ok && at < size; at += kPiece) {
    const size_t n = size_t(size - at < kPiece ? size - at : kPiece);
    ok = source->read(offset + at, n, buf);
    if (ok) c = crc32(buf, n, c);
  }
  munmap(map, kPiece);
  *crc = c;
  return ok;
}

Expected<std::unique_ptr<Engine>> Engine::load_image(const Source& source,
                                                     const EngineOptions& options) {
  if (const char* missing = kernels::missing_build_feature())
    return Error(Errc::kUnsupported,
                 "engine: this build assumes %s (compiled with -march=...), which this CPU does "
                 "not report; rebuild for the target's baseline (docs/architecture.md)",
                 missing);
  const uint8_t* const data = source.data;
  const size_t size = source.size;
  // Pass 1: validate everything (checksums included) and size.
  ParseOptions parse_options{.verify_checksums = options.verify_checksums};
  if (source.fd >= 0) {
    parse_options.section_crc = crc_from_file;
    parse_options.fetch = fetch_from_file;
    parse_options.source = const_cast<Source*>(&source);
  }
  auto checked = ModelFile::parse(data, size, parse_options);
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
  // Pass 2 binds to the source again (no second checksum pass); the
  // constants then move into the region.
  auto built = build(data, size, options, false, nullptr);
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
  uint8_t* const kept = region + m.tables_bytes;
  uint8_t* const packed = kept + m.kept_bytes;
  // Bind: packed weights, then the arena, then the scratch areas.
  uint8_t* cursor = packed;
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
  const size_t working_bytes = required - size_t(arena - region);
  e->ctx_.scratch = reinterpret_cast<float*>(cursor);
  cursor += round_up(e->scratch_floats_ * sizeof(float), kAlign);
  for (int t = 0; t < options.threads; ++t) {
    e->ctx_.thread_scratch[t] = reinterpret_cast<float*>(cursor);
    cursor += round_up(e->thread_scratch_floats_ * sizeof(float), kAlign);
  }
  // The arena and scratch are still unused: they hold the file's weights on
  // their way to being packed, so the load needs no buffer beside the block.
  if (Status s = e->place_constants(region, kept, source, arena, working_bytes); !s) {
    e.reset();
    if (owned) munmap(region, required);
    return s.error();
  }
  // Prefault: the arena and scratch are written once here, not during run()
  // (the kept and packed weights are written when they are placed).
  std::memset(arena, 0, working_bytes);
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

// The tables and the kept constants are copied into the region, the others
// packed by their ops (read from a file through a buffer of the largest op's
// packed inputs: `spare`, the block's not yet used arena and scratch, when
// they are large enough, else one allocated for the load); then nothing
// points into the source any more.
Status Engine::place_constants(uint8_t* tables, uint8_t* kept, const Source& source, uint8_t* spare,
                               size_t spare_bytes) {
  const uint8_t* const file = source.data;
  const size_t hole = size_t(model_.weights_offset()), hole_bytes = size_t(model_.weights_bytes());
  const size_t size = size_t(model_.file_bytes());
  std::memcpy(tables, file, hole);
  std::memcpy(tables + hole, file + hole + hole_bytes, size - hole - hole_bytes);
  const auto& entries = model_.tensors();
  auto file_offset = [&](size_t i) { return model_.weights_offset() + entries[i].data_offset; };
  auto index = [&](const Tensor* t) { return size_t(t - tensors_.data()); };
  for (size_t i = 0; i < tensors_.size(); ++i) {
    if (!kept_[i]) continue;
    Tensor& t = tensors_[i];
    APRT_ENSURE(source.read(file_offset(i), t.bytes, kept), Errc::kIo,
                "model_bin: cannot read tensor '%s' (file changed while loading?)", t.name);
    t.data = kept;
    kept += round_up(t.bytes, kAlign);
  }
  size_t bounce_bytes = 0;
  for (const OpNode& n : nodes_) {
    size_t need = 0;
    for (int k = 0; k < n.n_in; ++k) {
      if ((n.packed_inputs & (1u << k)) && !kept_[index(n.in[k])])
        need += round_up(n.in[k]->bytes, kAlign);
    }
    bounce_bytes = std::max(bounce_bytes, need);
  }
  std::unique_ptr<uint8_t[]> bounce;
  uint8_t* bounce_at = nullptr;
  if (source.fd >= 0 && bounce_bytes > 0) {
    if (bounce_bytes <= spare_bytes) {
      bounce_at = spare;  // kAlign-aligned: the arena's start
    } else {
      bounce.reset(new (std::nothrow) uint8_t[bounce_bytes + kAlign]);
      APRT_ENSURE(bounce != nullptr, Errc::kOutOfMemory,
                  "engine: out of memory for a %zu-byte load buffer", bounce_bytes);
      bounce_at =
          reinterpret_cast<uint8_t*>(round_up(reinterpret_cast<uintptr_t>(bounce.get()), kAlign));
    }
  }
  for (OpNode& n : nodes_) {
    if (!n.pack) continue;
    size_t used = 0;
    for (int k = 0; bounce_at && k < n.n_in; ++k) {
      Tensor* t = n.in[k];
      if (!(n.packed_inputs & (1u << k)) || kept_[index(t)]) continue;
      APRT_ENSURE(source.read(file_offset(index(t)), t->bytes, bounce_at + used), Errc::kIo,
                  "model_bin: cannot read tensor '%s' (file changed while loading?)", t->name);
      t->data = bounce_at + used;
      used += round_up(t->bytes, kAlign);
    }
    n.pack(n);
  }
  for (size_t i = 0; i < tensors_.size(); ++i) {
    if (tensors_[i].is_const() && !kept_[i]) tensors_[i].data = nullptr;
  }
  model_.relocate_tables(file, tables);
  for (size_t i = 0; i < tensors_.size(); ++i) tensors_[i].name = entries[i].name;
  const auto& ops = model_.ops();
  for (size_t i = 0; i < nodes_.size(); ++i) nodes_[i].name = ops[i].name;
  return ok();
}

namespace {

// A model file opened and its header read: never blocks on what is not a file
// (a FIFO, a device: refused at open), and a large file that is no model, or
// whose header disagrees with its size, is refused after 64 bytes. `got`:
// the header bytes read (fewer only for a file shorter than the header).
Expected<InputFile> open_model_file(const char* path, uint8_t (&head)[format::kHeaderBytes],
                                    long* got) {
  auto f = open_input_file(path, kMaxModelFileBytes, "model_bin");
  if (!f) return f.error();
  const uint64_t size = f->size();
  *got = f->read(head, size < sizeof head ? size_t(size) : sizeof head);
  APRT_ENSURE(*got >= 0, Errc::kIo, "model_bin: cannot read '%s': %s", path, std::strerror(errno));
  APRT_ENSURE(uint64_t(*got) == size || *got == long(sizeof head), Errc::kIo,
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
  return f;
}

}  // namespace

Expected<std::vector<uint8_t>> Engine::read_model_file(const char* path) {
  uint8_t head[format::kHeaderBytes];
  long got_head = 0;
  auto f = open_model_file(path, head, &got_head);
  if (!f) return f.error();
  const uint64_t size = f->size();
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
  // The file's header checked as read_model_file() does; then the tables are
  // read into a reservation the size of the file (untouched pages cost no
  // memory) and the weights from the file as load_image() places them. No
  // mapping of the file: one truncated while it loads is a read error, not SIGBUS.
  uint8_t head[format::kHeaderBytes] = {};
  long got = 0;
  auto f = open_model_file(path, head, &got);
  if (!f) return f.error();
  const uint64_t size = f->size();
  void* map = mmap(nullptr, size_t(size), PROT_READ | PROT_WRITE,
                   MAP_PRIVATE | MAP_ANONYMOUS | MAP_NORESERVE, -1, 0);
  APRT_ENSURE(map != MAP_FAILED, Errc::kOutOfMemory, "model_bin: cannot reserve %llu bytes: %s",
              static_cast<unsigned long long>(size), std::strerror(errno));
  auto* staging = static_cast<uint8_t*>(map);
  const Source source{staging, size_t(size), f->fd()};
  // Everything but the WEIGHTS section (found in the section table; if the
  // table is unreadable, the whole file, and parse() says what is wrong).
  uint64_t hole = size, hole_bytes = 0;
  if (size >= format::kHeaderBytes) {
    uint32_t count = 0;
    std::memcpy(&count, head + 24, 4);
    for (uint32_t i = 0; i < count && i < format::kMaxSections; ++i) {
      uint8_t entry[format::kSectionEntryBytes];
      const uint64_t at = format::kHeaderBytes + uint64_t(i) * format::kSectionEntryBytes;
      if (!source.read(at, sizeof entry, entry)) break;
      uint32_t tag = 0;
      uint64_t offset = 0, bytes = 0;
      std::memcpy(&tag, entry, 4);
      std::memcpy(&offset, entry + 8, 8);
      std::memcpy(&bytes, entry + 16, 8);
      if (tag == format::kSecWeights && offset <= size && bytes <= size - offset) {
        hole = offset;
        hole_bytes = bytes;
      }
    }
  }
  bool read_ok =
      source.read(0, size_t(hole), staging) &&
      source.read(hole + hole_bytes, size_t(size - hole - hole_bytes), staging + hole + hole_bytes);
  Expected<std::unique_ptr<Engine>> e =
      read_ok ? load_image(source, options)
              : Expected<std::unique_ptr<Engine>>(
                    Error(Errc::kIo, "model_bin: short read (file changed while read?)"));
  munmap(map, size_t(size));
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
