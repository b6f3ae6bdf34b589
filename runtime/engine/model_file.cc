#include "runtime/engine/model_file.h"

#include <cmath>
#include <cstring>

#include "runtime/base/check.h"
#include "runtime/base/crc32.h"
#include "runtime/engine/ensemble_merge.h"
#include "runtime/engine/model_bytes.h"

namespace aprt {

using format::DType;
using format::MetaKey;
using format::MetaType;
using format::TensorKind;

namespace {

const char* section_name(uint32_t tag) {
  switch (tag) {
    case format::kSecMeta: return "META";
    case format::kSecStrings: return "STRINGS";
    case format::kSecTensors: return "TENSORS";
    case format::kSecOps: return "OPS";
    case format::kSecWeights: return "WEIGHTS";
  }
  return "unknown";
}

struct Section {
  uint32_t tag = 0;
  uint64_t offset = 0;
  uint64_t size = 0;
  uint32_t crc = 0;
  const uint8_t* data = nullptr;
};

}  // namespace

class ModelFileParser {
 public:
  ModelFileParser(const uint8_t* data, size_t size, const ParseOptions& options)
      : data_(data), size_(size), options_(options) {}

  Expected<ModelFile> run() {
    if (Status s = header(); !s) return s.error();
    if (Status s = section_table(); !s) return s.error();
    if (Status s = strings(); !s) return s.error();
    if (Status s = meta(); !s) return s.error();
    if (Status s = tensor_table(); !s) return s.error();
    if (Status s = op_table(); !s) return s.error();
    if (Status s = graph_order(); !s) return s.error();
    return std::move(file_);
  }

 private:
  Status header() {
    APRT_ENSURE(size_ >= format::kHeaderBytes, Errc::kTruncated,
                "model_bin: file is %zu bytes, shorter than the %u-byte header (truncated?)", size_,
                format::kHeaderBytes);
    APRT_ENSURE(data_ != nullptr, Errc::kInvalidArgument, "model_bin: no data");
    APRT_ENSURE(std::memcmp(data_, format::kMagic, 8) == 0, Errc::kBadMagic,
                "model_bin: bad magic (not an aprt model file)");
    const uint16_t major = load<uint16_t>(data_ + 8);
    const uint16_t minor = load<uint16_t>(data_ + 10);
    APRT_ENSURE(load<uint32_t>(data_ + 28) == format::kEndianMark, Errc::kBadHeader,
                "model_bin: endianness mark 0x%08x (file written for another byte order?)",
                load<uint32_t>(data_ + 28));
    APRT_ENSURE(major == format::kVersionMajor, Errc::kUnsupportedVersion,
                "model_bin: unsupported version %u.%u (this build reads %u.x; re-convert the "
                "model with a matching aprt_tools)",
                major, minor, format::kVersionMajor);
    file_.version_major_ = major;
    file_.version_minor_ = minor;
    APRT_ENSURE(load<uint32_t>(data_ + 12) == format::kHeaderBytes, Errc::kBadHeader,
                "model_bin: header size %u, expected %u", load<uint32_t>(data_ + 12),
                format::kHeaderBytes);
    const uint64_t declared = load<uint64_t>(data_ + 16);
    APRT_ENSURE(declared <= size_, Errc::kTruncated,
                "model_bin: header says %llu bytes, file has %zu (file truncated?)",
                static_cast<unsigned long long>(declared), size_);
    APRT_ENSURE(declared == size_, Errc::kBadHeader,
                "model_bin: header says %llu bytes, file has %zu (trailing data?)",
                static_cast<unsigned long long>(declared), size_);
    file_.file_bytes_ = declared;
    APRT_ENSURE(load<uint32_t>(data_ + 32) == 0 && all_zero(data_ + 40, 24), Errc::kBadHeader,
                "model_bin: header flags or reserved bytes are not 0 (FORMAT.md: they must be; "
                "a file of another writer?)");
    section_count_ = load<uint32_t>(data_ + 24);
    APRT_ENSURE(section_count_ >= 1 && section_count_ <= format::kMaxSections, Errc::kBadHeader,
                "model_bin: %u sections (1..%u allowed)", section_count_, format::kMaxSections);
    const uint64_t table_end =
        format::kHeaderBytes + uint64_t(section_count_) * format::kSectionEntryBytes;
    APRT_ENSURE(table_end <= size_, Errc::kTruncated,
                "model_bin: section table ends at %llu, past the end of the file (truncated?)",
                static_cast<unsigned long long>(table_end));
    if (options_.verify_checksums) {
      uint8_t head[format::kHeaderBytes];
      std::memcpy(head, data_, sizeof head);
      std::memset(head + 36, 0, 4);
      uint32_t crc = crc32(head, sizeof head);
      crc = crc32(data_ + format::kHeaderBytes, table_end - format::kHeaderBytes, crc);
      APRT_ENSURE(crc == load<uint32_t>(data_ + 36), Errc::kChecksum,
                  "model_bin: header checksum mismatch (header or section table corrupted)");
    }
    return ok();
  }

  Status section_table() {
    for (uint32_t i = 0; i < section_count_; ++i) {
      const uint8_t* e = data_ + format::kHeaderBytes + i * format::kSectionEntryBytes;
      Section s;
      s.tag = load<uint32_t>(e);
      s.offset = load<uint64_t>(e + 8);
      s.size = load<uint64_t>(e + 16);
      s.crc = load<uint32_t>(e + 24);
      const char* name = section_name(s.tag);
      APRT_ENSURE(load<uint32_t>(e + 4) == 0 && load<uint32_t>(e + 28) == 0, Errc::kBadHeader,
                  "model_bin: section %s: flags or reserved field not 0", name);
      APRT_ENSURE(s.offset % format::kAlign == 0, Errc::kMisaligned,
                  "model_bin: section %s offset %llu is not %u-byte aligned", name,
                  static_cast<unsigned long long>(s.offset), format::kAlign);
      APRT_ENSURE(s.offset <= size_ && s.size <= size_ - s.offset, Errc::kSectionBounds,
                  "model_bin: section %s [%llu, +%llu) lies outside the %zu-byte file "
                  "(truncated?)",
                  name, static_cast<unsigned long long>(s.offset),
                  static_cast<unsigned long long>(s.size), size_);
      APRT_ENSURE(s.offset >= format::kHeaderBytes + section_count_ * format::kSectionEntryBytes,
                  Errc::kSectionBounds, "model_bin: section %s overlaps the header", name);
      for (uint32_t j = 0; j < n_sections_; ++j) {
        const Section& o = sections_[j];
        APRT_ENSURE(o.tag != s.tag, Errc::kSectionBounds, "model_bin: section %s appears twice",
                    name);
        const bool disjoint = s.offset + s.size <= o.offset || o.offset + o.size <= s.offset;
        APRT_ENSURE(disjoint, Errc::kSectionBounds, "model_bin: sections %s and %s overlap", name,
                    section_name(o.tag));
      }
      s.data = data_ + s.offset;
      sections_[n_sections_++] = s;  // unknown tags are kept but ignored (minor versions)
    }
    // Checksums after the structure, so that a structural defect gets its own message.
    for (uint32_t i = 0; i < n_sections_ && options_.verify_checksums; ++i) {
      const Section& s = sections_[i];
      uint32_t crc = 0;
      if (options_.section_crc) {
        APRT_ENSURE(options_.section_crc(options_.source, s.offset, s.size, &crc), Errc::kIo,
                    "model_bin: section %s: cannot read the file (changed while read?)",
                    section_name(s.tag));
      } else {
        crc = crc32(s.data, s.size);
      }
      APRT_ENSURE(crc == s.crc, Errc::kChecksum,
                  "model_bin: section %s checksum mismatch (file corrupted or truncated?)",
                  section_name(s.tag));
    }
    for (uint32_t tag : {format::kSecMeta, format::kSecStrings, format::kSecTensors,
                         format::kSecOps, format::kSecWeights}) {
      APRT_ENSURE(find(tag) != nullptr, Errc::kSectionBounds,
                  "model_bin: required section %s is missing", section_name(tag));
    }
    return ok();
  }

  const Section* find(uint32_t tag) const {
    for (uint32_t i = 0; i < n_sections_; ++i) {
      if (sections_[i].tag == tag) return &sections_[i];
    }
    return nullptr;
  }

  Status strings() {
    const Section* s = find(format::kSecStrings);
    APRT_ENSURE(s->size >= 1 && s->data[s->size - 1] == '\0', Errc::kBadHeader,
                "model_bin: string table is empty or not NUL-terminated");
    strings_ = s;
    return ok();
  }

  // A string-table reference, or an error naming `what`.
  Expected<const char*> string_at(uint32_t offset, const char* what) const {
    APRT_ENSURE(offset < strings_->size, Errc::kBadHeader,
                "model_bin: %s name offset %u is outside the string table", what, offset);
    return reinterpret_cast<const char*>(strings_->data + offset);
  }

  Status meta() {
    const Section* s = find(format::kSecMeta);
    return parse_model_meta(s->data, s->size, &file_.meta_);
  }

  Status table_prefix(const Section* s, uint32_t entry_bytes, uint32_t max_count, const char* what,
                      uint32_t* count) {
    APRT_ENSURE(s->size >= format::kTablePrefixBytes, Errc::kTruncated,
                "model_bin: %s table has no header", what);
    *count = load<uint32_t>(s->data);
    APRT_ENSURE(load<uint32_t>(s->data + 4) == entry_bytes, Errc::kBadHeader,
                "model_bin: %s entries are %u bytes, expected %u", what,
                load<uint32_t>(s->data + 4), entry_bytes);
    APRT_ENSURE(all_zero(s->data + 8, 8), Errc::kBadHeader,
                "model_bin: %s table header: reserved words not 0", what);
    APRT_ENSURE(*count >= 1 && *count <= max_count, Errc::kTooLarge,
                "model_bin: %u %s entries (1..%u allowed)", *count, what, max_count);
    APRT_ENSURE(s->size == format::kTablePrefixBytes + uint64_t(*count) * entry_bytes,
                Errc::kSectionBounds, "model_bin: %s table size %llu does not fit %u entries", what,
                static_cast<unsigned long long>(s->size), *count);
    return ok();
  }

  Status tensor_table() {
    const Section* s = find(format::kSecTensors);
    const Section* w = find(format::kSecWeights);
    file_.weights_ = w->data;
    file_.weights_bytes_ = w->size;
    file_.weights_offset_ = w->offset;
    uint32_t count = 0;
    if (Status st =
            table_prefix(s, format::kTensorEntryBytes, format::kMaxTensors, "tensor", &count);
        !st) {
      return st;
    }
    file_.tensors_.resize(count);
    for (uint32_t i = 0; i < count; ++i) {
      const uint8_t* e = s->data + format::kTablePrefixBytes + i * format::kTensorEntryBytes;
      TensorEntry& t = file_.tensors_[i];
      auto name = string_at(load<uint32_t>(e), "tensor");
      if (!name) return name.error();
      t.name = *name;
      const uint8_t dtype = e[4];
      t.rank = e[5];
      const uint8_t kind = e[6];
      APRT_ENSURE(e[7] == 0 && all_zero(e + 52, 12), Errc::kBadTensor,
                  "model_bin: tensor %u '%s': flags or reserved bytes not 0", i, t.name);
      APRT_ENSURE(dtype >= 1 && dtype <= 4, Errc::kBadTensor,
                  "model_bin: tensor %u '%s' has unknown dtype %u", i, t.name, dtype);
      APRT_ENSURE(kind >= 1 && kind <= 4, Errc::kBadTensor,
                  "model_bin: tensor %u '%s' has unknown kind %u", i, t.name, kind);
      APRT_ENSURE(t.rank >= 1 && t.rank <= format::kMaxRank, Errc::kBadTensor,
                  "model_bin: tensor %u '%s' has rank %d (1..%d allowed)", i, t.name, t.rank,
                  format::kMaxRank);
      t.dtype = static_cast<DType>(dtype);
      t.kind = static_cast<TensorKind>(kind);
      t.numel = 1;
      for (int d = 0; d < format::kMaxRank; ++d) {
        t.dims[d] = load<uint32_t>(e + 8 + 4 * d);
        if (d >= t.rank) {
          APRT_ENSURE(t.dims[d] == 0, Errc::kBadTensor,
                      "model_bin: tensor '%s' has a non-zero dimension beyond its rank", t.name);
          continue;
        }
        APRT_ENSURE(t.dims[d] >= 1 && t.dims[d] <= format::kMaxDim, Errc::kTooLarge,
                    "model_bin: tensor '%s' dimension %d is %u (1..%u allowed)", t.name, d,
                    t.dims[d], format::kMaxDim);
        t.numel *= t.dims[d];
        APRT_ENSURE(t.numel <= format::kMaxTensorElements, Errc::kTooLarge,
                    "model_bin: tensor '%s' has more than %llu elements", t.name,
                    static_cast<unsigned long long>(format::kMaxTensorElements));
      }
      t.bytes = t.numel * format::dtype_bytes(t.dtype);
      t.data_offset = load<uint64_t>(e + 24);
      const uint64_t data_bytes = load<uint64_t>(e + 32);
      t.scale = load<float>(e + 40);
      t.zero_point = load<int32_t>(e + 44);
      t.qscale_tensor = load<int32_t>(e + 48);
      if (t.kind == TensorKind::kConst) {
        APRT_ENSURE(data_bytes == t.bytes, Errc::kBadTensor,
                    "model_bin: constant '%s' stores %llu bytes, its shape needs %llu", t.name,
                    static_cast<unsigned long long>(data_bytes),
                    static_cast<unsigned long long>(t.bytes));
        APRT_ENSURE(t.data_offset % format::kAlign == 0, Errc::kMisaligned,
                    "model_bin: constant '%s' data offset %llu is not %u-byte aligned", t.name,
                    static_cast<unsigned long long>(t.data_offset), format::kAlign);
        APRT_ENSURE(
            t.data_offset <= w->size && t.bytes <= w->size - t.data_offset, Errc::kSectionBounds,
            "model_bin: constant '%s' data [%llu, +%llu) lies outside WEIGHTS (%llu "
            "bytes)",
            t.name, static_cast<unsigned long long>(t.data_offset),
            static_cast<unsigned long long>(t.bytes), static_cast<unsigned long long>(w->size));
      } else {
        APRT_ENSURE(data_bytes == 0 && t.data_offset == 0, Errc::kBadTensor,
                    "model_bin: non-constant tensor '%s' claims weight data", t.name);
      }
      APRT_ENSURE(std::isfinite(t.scale) && t.scale >= 0.0f, Errc::kBadTensor,
                  "model_bin: tensor '%s' quantisation scale %g (must be > 0, or 0 for none)",
                  t.name, t.scale);
      if (t.scale > 0.0f) {
        const bool i8 = t.dtype == DType::kI8;
        APRT_ENSURE(i8 || t.dtype == DType::kU8, Errc::kBadTensor,
                    "model_bin: tensor '%s' is quantised but of type %s", t.name,
                    format::dtype_name(t.dtype));
        const int lo = i8 ? -128 : 0, hi = i8 ? 127 : 255;
        APRT_ENSURE(t.zero_point >= lo && t.zero_point <= hi, Errc::kBadTensor,
                    "model_bin: tensor '%s' zero point %d out of range [%d, %d]", t.name,
                    t.zero_point, lo, hi);
      }
      APRT_ENSURE(t.qscale_tensor >= -1 && t.qscale_tensor < int32_t(count), Errc::kBadTensor,
                  "model_bin: tensor '%s' per-channel scale index %d out of range", t.name,
                  t.qscale_tensor);
      if (t.kind == TensorKind::kInput) {
        APRT_ENSURE(file_.input_ < 0, Errc::kBadGraph, "model_bin: more than one input tensor");
        file_.input_ = int(i);
      }
      if (t.kind == TensorKind::kOutput) {
        APRT_ENSURE(file_.output_ < 0, Errc::kBadGraph, "model_bin: more than one output tensor");
        file_.output_ = int(i);
      }
    }
    if (Status st = quantisation(); !st) return st;
    APRT_ENSURE(file_.input_ >= 0, Errc::kBadGraph, "model_bin: no input tensor");
    APRT_ENSURE(file_.output_ >= 0, Errc::kBadGraph, "model_bin: no output tensor");
    const TensorEntry& in = file_.tensors_[file_.input_];
    bool shape_ok = in.rank == 4 && in.dtype == DType::kF32;
    for (int d = 0; d < 4 && shape_ok; ++d) shape_ok = in.dims[d] == file_.meta_.input_shape[d];
    APRT_ENSURE(shape_ok, Errc::kBadMetadata,
                "model_bin: input tensor '%s' does not match the metadata input shape "
                "%ux%ux%ux%u (f32 NHWC)",
                in.name, file_.meta_.input_shape[0], file_.meta_.input_shape[1],
                file_.meta_.input_shape[2], file_.meta_.input_shape[3]);
    APRT_ENSURE(in.dims[0] == 1, Errc::kUnsupported, "model_bin: batch size %u (only 1)",
                in.dims[0]);
    const TensorEntry& out = file_.tensors_[file_.output_];
    const uint32_t members = file_.meta_.ensemble_members;
    const bool with_members = members >= 2 && members <= uint32_t(kMaxEnsembleMembers) &&
                              out.numel == uint64_t(kNetworkOutputs) * members;
    APRT_ENSURE(out.dtype == DType::kF32 && (out.numel == 7 || out.numel == 13 || with_members),
                Errc::kBadGraph,
                "model_bin: output '%s' must be 7 f32 values (x y z qw qx qy qz), 13 with "
                "the confidence outputs, or 13 per member of an ensemble (META 'ensemble' "
                "= %u), has %llu %s",
                out.name, unsigned(members), static_cast<unsigned long long>(out.numel),
                format::dtype_name(out.dtype));
    file_.meta_.member_outputs = with_members ? members : 0;
    APRT_ENSURE((out.numel >= 13) == file_.meta_.has_uncertainty, Errc::kBadMetadata, "%s",
                out.numel >= 13
                    ? "model_bin: the model has confidence outputs but no 'uncertainty' "
                      "calibration (python3 -m aprt_tools confidence MODEL --val DRIVE)"
                    : "model_bin: metadata 'uncertainty' without the confidence outputs "
                      "(the output has 7 values, not 13)");
    return ok();
  }

  // Quantised constants (FORMAT.md, "Quantised ops"): an i8/u8 tensor is a
  // constant with a per-tensor scale or per-channel scales, never both; the
  // per-channel scales are an f32 constant [dims[0]] of finite positive values.
  Status quantisation() {
    const auto& ts = file_.tensors_;
    for (const TensorEntry& t : ts) {
      const bool integer = t.dtype == DType::kI8 || t.dtype == DType::kU8;
      if (!integer) {
        APRT_ENSURE(t.qscale_tensor < 0, Errc::kBadTensor,
                    "model_bin: tensor '%s' of type %s has per-channel quantisation scales", t.name,
                    format::dtype_name(t.dtype));
        continue;
      }
      APRT_ENSURE(t.kind == TensorKind::kConst, Errc::kUnsupported,
                  "model_bin: tensor '%s' is %s but not a constant (integer activations are not "
                  "supported; ops quantise their inputs themselves)",
                  t.name, format::dtype_name(t.dtype));
      APRT_ENSURE((t.scale > 0.0f) != (t.qscale_tensor >= 0), Errc::kBadTensor,
                  "model_bin: quantised tensor '%s' needs exactly one of a per-tensor scale or "
                  "per-channel scales (has %s)",
                  t.name, t.scale > 0.0f ? "both" : "neither");
      if (t.qscale_tensor < 0) continue;
      const TensorEntry& q = ts[size_t(t.qscale_tensor)];
      // Channels are the first axis of LINEAR weights, the last of depthwise ones.
      const uint32_t first = t.dims[0], last = t.dims[t.rank - 1];
      APRT_ENSURE(q.dtype == DType::kF32 && q.kind == TensorKind::kConst && q.rank == 1 &&
                      (q.numel == first || q.numel == last),
                  Errc::kBadTensor,
                  "model_bin: per-channel scales '%s' of '%s' must be an f32 constant of one "
                  "value per channel (%u, or %u for depthwise weights)",
                  q.name, t.name, first, last);
      if (options_.fetch) {
        APRT_ENSURE(options_.fetch(options_.source, file_.weights_offset_ + q.data_offset, q.bytes),
                    Errc::kIo, "model_bin: cannot read '%s' (file changed while read?)", q.name);
      }
      const uint8_t* base = file_.weights_ + q.data_offset;
      for (uint64_t j = 0; j < q.numel; ++j) {
        const float v = load<float>(base + 4 * j);
        APRT_ENSURE(std::isfinite(v) && v > 0.0f, Errc::kBadTensor,
                    "model_bin: per-channel scale %llu of '%s' is %g (must be finite and > 0)",
                    static_cast<unsigned long long>(j), t.name, double(v));
      }
    }
    return ok();
  }

  Status op_table() {
    const Section* s = find(format::kSecOps);
    uint32_t count = 0;
    if (Status st = table_prefix(s, format::kOpEntryBytes, format::kMaxOps, "op", &count); !st) {
      return st;
    }
    file_.ops_.resize(count);
    const int32_t n_tensors = int32_t(file_.tensors_.size());
    for (uint32_t i = 0; i < count; ++i) {
      const uint8_t* e = s->data + format::kTablePrefixBytes + i * format::kOpEntryBytes;
      OpEntry& op = file_.ops_[i];
      const uint16_t code = load<uint16_t>(e);
      op.n_in = e[2];
      op.n_out = e[3];
      auto name = string_at(load<uint32_t>(e + 4), "op");
      if (!name) return name.error();
      op.name = *name;
      APRT_ENSURE(code >= 1 && code <= format::kMaxOpCode, Errc::kBadOp,
                  "model_bin: op %u '%s' has unknown opcode %u (model needs a newer aprt?)", i,
                  op.name, code);
      op.code = static_cast<format::OpCode>(code);
      APRT_ENSURE(op.n_in >= 1 && op.n_in <= format::kMaxOpInputs && op.n_out >= 1 &&
                      op.n_out <= format::kMaxOpOutputs,
                  Errc::kBadOp, "model_bin: op %u '%s' has %d inputs and %d outputs", i, op.name,
                  op.n_in, op.n_out);
      for (int k = 0; k < format::kMaxOpInputs; ++k) {
        op.in[k] = load<int32_t>(e + 8 + 4 * k);
        const bool ok_index =
            (op.in[k] >= -1 && op.in[k] < n_tensors) && (k < op.n_in || op.in[k] == -1);
        APRT_ENSURE(ok_index, Errc::kBadOp, "model_bin: op %u '%s' input %d index %d invalid", i,
                    op.name, k, op.in[k]);
      }
      for (int k = 0; k < format::kMaxOpOutputs; ++k) {
        op.out[k] = load<int32_t>(e + 40 + 4 * k);
        const bool ok_index =
            k < op.n_out ? (op.out[k] >= 0 && op.out[k] < n_tensors) : op.out[k] == -1;
        APRT_ENSURE(ok_index, Errc::kBadOp, "model_bin: op %u '%s' output %d index %d invalid", i,
                    op.name, k, op.out[k]);
      }
      for (int k = 0; k < format::kMaxOpParams; ++k) op.params[k] = load<int32_t>(e + 48 + 4 * k);
    }
    return ok();
  }

  // Every activation/output is written by exactly one op, before any op reads it;
  // constants and the input are never written; the output is written.
  Status graph_order() {
    std::vector<uint8_t> defined(file_.tensors_.size(), 0);
    for (size_t t = 0; t < file_.tensors_.size(); ++t) {
      const TensorKind k = file_.tensors_[t].kind;
      defined[t] = (k == TensorKind::kConst || k == TensorKind::kInput) ? 1 : 0;
    }
    for (size_t i = 0; i < file_.ops_.size(); ++i) {
      const OpEntry& op = file_.ops_[i];
      for (int k = 0; k < op.n_in; ++k) {
        if (op.in[k] < 0) continue;
        APRT_ENSURE(defined[op.in[k]], Errc::kBadGraph,
                    "model_bin: op %zu '%s' reads tensor '%s' before anything writes it", i,
                    op.name, file_.tensors_[op.in[k]].name);
      }
      for (int k = 0; k < op.n_out; ++k) {
        const TensorEntry& t = file_.tensors_[op.out[k]];
        APRT_ENSURE(t.kind == TensorKind::kActivation || t.kind == TensorKind::kOutput,
                    Errc::kBadGraph, "model_bin: op %zu '%s' writes %s tensor '%s'", i, op.name,
                    t.kind == TensorKind::kConst ? "constant" : "input", t.name);
        APRT_ENSURE(!defined[op.out[k]], Errc::kBadGraph,
                    "model_bin: tensor '%s' is written twice (second time by op %zu '%s')", t.name,
                    i, op.name);
        defined[op.out[k]] = 1;
      }
    }
    APRT_ENSURE(defined[file_.output_], Errc::kBadGraph, "model_bin: no op writes the output '%s'",
                file_.tensors_[file_.output_].name);
    return ok();
  }

  const uint8_t* data_;
  size_t size_;
  ParseOptions options_;
  uint32_t section_count_ = 0;
  Section sections_[format::kMaxSections];
  uint32_t n_sections_ = 0;
  const Section* strings_ = nullptr;
  ModelFile file_;
};

void ModelFile::relocate_tables(const uint8_t* file, const uint8_t* tables) {
  const uint64_t hole_begin = weights_offset_, hole_end = weights_offset_ + weights_bytes_;
  auto move = [&](const char* p) -> const char* {
    if (!p) return p;
    uint64_t at = uint64_t(reinterpret_cast<const uint8_t*>(p) - file);
    APRT_DCHECK(at < hole_begin || (at >= hole_end && at < file_bytes_));
    (void)hole_begin;
    if (at >= hole_end) at -= weights_bytes_;
    return reinterpret_cast<const char*>(tables + at);
  };
  meta_.config_json = move(meta_.config_json);
  meta_.quantization = move(meta_.quantization);
  for (TensorEntry& t : tensors_) t.name = move(t.name);
  for (OpEntry& o : ops_) o.name = move(o.name);
  weights_ = nullptr;
}

Expected<ModelFile> ModelFile::parse(const uint8_t* data, size_t size,
                                     const ParseOptions& options) {
  static_assert(sizeof(float) == 4 && sizeof(double) == 8);
  const uint32_t probe = 1;
  APRT_ENSURE(*reinterpret_cast<const uint8_t*>(&probe) == 1, Errc::kUnsupported,
              "model_bin: big-endian hosts are not supported");
  ModelFileParser parser(data, size, options);
  return parser.run();
}

}  // namespace aprt
