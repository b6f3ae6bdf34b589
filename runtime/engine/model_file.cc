#include "runtime/engine/model_file.h"

#include <cmath>
#include <cstring>

#include "runtime/base/check.h"
#include "runtime/base/crc32.h"

namespace aprt {

using format::DType;
using format::MetaKey;
using format::MetaType;
using format::TensorKind;

namespace format {

size_t dtype_bytes(DType t) noexcept {
  switch (t) {
    case DType::kF32: return 4;
    case DType::kI8: return 1;
    case DType::kI32: return 4;
    case DType::kU8: return 1;
  }
  return 0;
}

const char* dtype_name(DType t) noexcept {
  switch (t) {
    case DType::kF32: return "f32";
    case DType::kI8: return "i8";
    case DType::kI32: return "i32";
    case DType::kU8: return "u8";
  }
  return "?";
}

const char* op_name(OpCode code) noexcept {
  switch (code) {
    case OpCode::kConv2d: return "CONV2D";
    case OpCode::kDwConv2d: return "DWCONV2D";
    case OpCode::kLinear: return "LINEAR";
    case OpCode::kSqueezeExcite: return "SQUEEZE_EXCITE";
    case OpCode::kAdd: return "ADD";
    case OpCode::kLayerNorm: return "LAYERNORM";
    case OpCode::kAttention: return "ATTENTION";
    case OpCode::kActivation: return "ACTIVATION";
    case OpCode::kConcat: return "CONCAT";
    case OpCode::kCrossAttention1q: return "CROSS_ATTENTION_1Q";
    case OpCode::kFps: return "FPS";
    case OpCode::kBallGroup: return "BALL_GROUP";
    case OpCode::kGroupMax: return "GROUP_MAX";
    case OpCode::kThreeInterp: return "THREE_INTERP";
    case OpCode::kGridTokens: return "GRID_TOKENS";
  }
  return "?";
}

const char* modality_name(Modality m) noexcept {
  switch (m) {
    case Modality::kImage: return "image";
    case Modality::kLidarBev: return "lidar_bev";
    case Modality::kLidarPoints: return "lidar_points";
  }
  return "?";
}

const char* act_name(Act a) noexcept {
  switch (a) {
    case Act::kNone: return "none";
    case Act::kSilu: return "silu";
    case Act::kGelu: return "gelu";
    case Act::kSigmoid: return "sigmoid";
    case Act::kRelu: return "relu";
  }
  return "?";
}

}  // namespace format

namespace {

template <class T>
T load(const uint8_t* p) {
  T v;
  std::memcpy(&v, p, sizeof(T));
  return v;
}

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
      APRT_ENSURE(crc32(s.data, s.size) == s.crc, Errc::kChecksum,
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

  static void copy_str(char* dst, size_t cap, const uint8_t* src, size_t n) {
    const size_t k = n < cap - 1 ? n : cap - 1;
    std::memcpy(dst, src, k);
    dst[k] = '\0';
  }

  Status meta() {
    const Section* s = find(format::kSecMeta);
    ModelMeta& m = file_.meta_;
    uint64_t seen = 0;  // bit per known key index
    auto mark = [&](int bit) { seen |= uint64_t(1) << bit; };
    uint64_t pos = 0;
    while (pos < s->size) {
      APRT_ENSURE(s->size - pos >= 8, Errc::kBadMetadata,
                  "model_bin: META record header at byte %llu is cut off",
                  static_cast<unsigned long long>(pos));
      const auto key = static_cast<MetaKey>(load<uint16_t>(s->data + pos));
      const auto type = static_cast<MetaType>(load<uint16_t>(s->data + pos + 2));
      const uint32_t len = load<uint32_t>(s->data + pos + 4);
      APRT_ENSURE(len <= s->size - pos - 8, Errc::kBadMetadata,
                  "model_bin: META key %u claims %u bytes, past the section end", unsigned(key),
                  len);
      const uint8_t* v = s->data + pos + 8;
      auto expect = [&](MetaType t, uint32_t min_count, uint32_t max_count) -> Status {
        APRT_ENSURE(type == t, Errc::kBadMetadata,
                    "model_bin: META key %u has type %u, expected %u", unsigned(key),
                    unsigned(type), unsigned(t));
        const uint32_t unit = (t == MetaType::kU32 || t == MetaType::kF32) ? 4 : 1;
        APRT_ENSURE(len % unit == 0 && len / unit >= min_count && len / unit <= max_count,
                    Errc::kBadMetadata, "model_bin: META key %u has %u bytes (wrong count)",
                    unsigned(key), len);
        return ok();
      };
      auto f32s = [&](float* dst, uint32_t n, const char* what) -> Status {
        for (uint32_t i = 0; i < n; ++i) {
          dst[i] = load<float>(v + 4 * i);
          APRT_ENSURE(std::isfinite(dst[i]), Errc::kBadMetadata,
                      "model_bin: metadata %s[%u] is not finite", what, i);
        }
        return ok();
      };
      Status st;
      switch (key) {
        case MetaKey::kProducer:
          if (!(st = expect(MetaType::kStr, 0, 4096))) return st;
          copy_str(m.producer, sizeof m.producer, v, len);
          mark(0);
          break;
        case MetaKey::kSourceSha256:
          if (!(st = expect(MetaType::kBytes, 32, 32))) return st;
          std::memcpy(m.source_sha256, v, 32);
          mark(1);
          break;
        case MetaKey::kSourceName:
          if (!(st = expect(MetaType::kStr, 0, 4096))) return st;
          copy_str(m.source_name, sizeof m.source_name, v, len);
          break;
        case MetaKey::kModality: {
          if (!(st = expect(MetaType::kU32, 1, 1))) return st;
          const uint32_t mod = load<uint32_t>(v);
          APRT_ENSURE(mod >= 1 && mod <= 3, Errc::kBadMetadata, "model_bin: unknown modality %u",
                      mod);
          m.modality = static_cast<format::Modality>(mod);
          mark(2);
          break;
        }
        case MetaKey::kInputShape:
          if (!(st = expect(MetaType::kU32, 4, 4))) return st;
          for (int i = 0; i < 4; ++i) m.input_shape[i] = load<uint32_t>(v + 4 * i);
          mark(3);
          break;
        case MetaKey::kNormMean:
          if (!(st = expect(MetaType::kF32, 1, ModelMeta::kMaxChannels))) return st;
          m.norm_channels = int(len / 4);
          if (!(st = f32s(m.norm_mean, len / 4, "norm_mean"))) return st;
          mark(4);
          break;
        case MetaKey::kNormStd:
          if (!(st = expect(MetaType::kF32, 1, ModelMeta::kMaxChannels))) return st;
          if (!(st = f32s(m.norm_std, len / 4, "norm_std"))) return st;
          for (uint32_t i = 0; i < len / 4; ++i) {
            APRT_ENSURE(m.norm_std[i] > 0.0f, Errc::kBadMetadata,
                        "model_bin: norm_std[%u] = %g must be positive", i, m.norm_std[i]);
          }
          APRT_ENSURE(int(len / 4) == m.norm_channels || m.norm_channels == 0, Errc::kBadMetadata,
                      "model_bin: norm_mean and norm_std have different lengths");
          mark(5);
          break;
        case MetaKey::kResizePolicy: {
          if (!(st = expect(MetaType::kU32, 1, 1))) return st;
          const uint32_t r = load<uint32_t>(v);
          APRT_ENSURE(r == 1 || r == 2, Errc::kBadMetadata, "model_bin: unknown resize policy %u",
                      r);
          m.resize_policy = static_cast<format::ResizePolicy>(r);
          break;
        }
        case MetaKey::kPoseMin:
          if (!(st = expect(MetaType::kF32, 3, 3))) return st;
          if (!(st = f32s(m.pose_min, 3, "pose_min"))) return st;
          mark(6);
          break;
        case MetaKey::kPoseMax:
          if (!(st = expect(MetaType::kF32, 3, 3))) return st;
          if (!(st = f32s(m.pose_max, 3, "pose_max"))) return st;
          mark(7);
          break;
        case MetaKey::kBackbone:
          if (!(st = expect(MetaType::kStr, 0, 4096))) return st;
          copy_str(m.backbone, sizeof m.backbone, v, len);
          break;
        case MetaKey::kDModel:
        case MetaKey::kNHeads:
        case MetaKey::kEncLayers:
        case MetaKey::kDecLayers:
        case MetaKey::kDimFeedforward: {
          if (!(st = expect(MetaType::kU32, 1, 1))) return st;
          const uint32_t x = load<uint32_t>(v);
          APRT_ENSURE(x <= 65536, Errc::kBadMetadata, "model_bin: META key %u = %u is absurd",
                      unsigned(key), x);
          if (key == MetaKey::kDModel) m.d_model = x, mark(8);
          if (key == MetaKey::kNHeads) m.nheads = x, mark(9);
          if (key == MetaKey::kEncLayers) m.enc_layers = x, mark(10);
          if (key == MetaKey::kDecLayers) m.dec_layers = x, mark(11);
          if (key == MetaKey::kDimFeedforward) m.dim_feedforward = x;
          break;
        }
        case MetaKey::kValError: {
          if (!(st = expect(MetaType::kF32, 2, 2))) return st;
          float e[2] = {0.0f, 0.0f};
          if (!(st = f32s(e, 2, "val_error"))) return st;
          APRT_ENSURE(e[0] >= 0 && e[1] >= 0, Errc::kBadMetadata,
                      "model_bin: negative validation error");
          m.has_val_error = true;
          m.val_error_position_m = e[0];
          m.val_error_orientation_deg = e[1];
          break;
        }
        case MetaKey::kConfigJson:
          if (!(st = expect(MetaType::kStr, 0, 1u << 20))) return st;
          m.config_json = reinterpret_cast<const char*>(v);
          m.config_json_bytes = len;
          break;
        case MetaKey::kBev: {
          if (!(st = expect(MetaType::kF32, 5, 5))) return st;
          float b[5];
          if (!(st = f32s(b, 5, "bev"))) return st;
          APRT_ENSURE(b[0] > 0.0f && b[0] <= 10.0f, Errc::kBadMetadata,
                      "model_bin: BEV cell size %g m (0 < cell <= 10)", double(b[0]));
          APRT_ENSURE(b[4] >= 1.0f && b[4] <= 65536.0f, Errc::kBadMetadata,
                      "model_bin: BEV clip count %g (1..65536)", double(b[4]));
          m.has_bev = true;
          m.bev_cell_m = b[0];
          m.bev_x_min = b[1];
          m.bev_y_min = b[2];
          m.bev_height_threshold_m = b[3];
          m.bev_clip_count = b[4];
          break;
        }
        case MetaKey::kPoints: {
          if (!(st = expect(MetaType::kF32, 2, 2))) return st;
          float p[2] = {0.0f, 0.0f};
          if (!(st = f32s(p, 2, "points"))) return st;
          APRT_ENSURE(p[0] > 0.0f && p[0] <= 1000.0f, Errc::kBadMetadata,
                      "model_bin: points crop radius %g m (0 < radius <= 1000)", double(p[0]));
          APRT_ENSURE(p[1] > 0.0f && p[1] <= 1000.0f, Errc::kBadMetadata,
                      "model_bin: points coordinate scale %g m (0 < scale <= 1000)", double(p[1]));
          m.has_points = true;
          m.points_crop_radius_m = p[0];
          m.points_coord_scale_m = p[1];
          break;
        }
        case MetaKey::kQuantization:
          if (!(st = expect(MetaType::kStr, 0, 1u << 16))) return st;
          m.quantization = reinterpret_cast<const char*>(v);
          m.quantization_bytes = len;
          break;
        default: break;  // unknown keys: written by a newer minor version, ignored
      }
      pos += 8 + ((uint64_t(len) + 3) & ~uint64_t(3));
    }
    static const char* const kRequired[] = {
        "producer", "source_sha256", "modality", "input_shape", "norm_mean",  "norm_std",
        "pose_min", "pose_max",      "d_model",  "nheads",      "enc_layers", "dec_layers"};
    for (int bit = 0; bit < 12; ++bit) {
      APRT_ENSURE(seen & (uint64_t(1) << bit), Errc::kBadMetadata,
                  "model_bin: required metadata '%s' is missing", kRequired[bit]);
    }
    for (int i = 0; i < 3; ++i) {
      APRT_ENSURE(m.pose_min[i] < m.pose_max[i], Errc::kBadMetadata,
                  "model_bin: pose bounds axis %d: min %g >= max %g", i, m.pose_min[i],
                  m.pose_max[i]);
    }
    APRT_ENSURE(m.nheads > 0 && m.d_model > 0 && m.d_model % m.nheads == 0, Errc::kBadMetadata,
                "model_bin: d_model %u is not a positive multiple of nheads %u", m.d_model,
                m.nheads);
    APRT_ENSURE(int(m.input_shape[3]) == m.norm_channels, Errc::kBadMetadata,
                "model_bin: %d normalisation values for %u input channels", m.norm_channels,
                m.input_shape[3]);
    if (m.modality == format::Modality::kLidarBev) {
      APRT_ENSURE(m.has_bev, Errc::kBadMetadata,
                  "model_bin: a LiDAR BEV model needs metadata 'bev' (cell size, origin, height "
                  "threshold, clip count)");
      APRT_ENSURE(m.input_shape[1] == m.input_shape[2] && m.input_shape[3] == 2, Errc::kBadMetadata,
                  "model_bin: a LiDAR BEV input is a square 2-channel grid, not %ux%ux%u",
                  m.input_shape[1], m.input_shape[2], m.input_shape[3]);
    }
    if (m.modality == format::Modality::kLidarPoints) {
      APRT_ENSURE(m.has_points, Errc::kBadMetadata,
                  "model_bin: a LiDAR points model needs metadata 'points' (crop radius, "
                  "coordinate scale)");
      APRT_ENSURE(m.input_shape[2] == 1 && m.input_shape[3] == 6, Errc::kBadMetadata,
                  "model_bin: a LiDAR points input is N points x 1 x 6 features, not %ux%ux%u",
                  m.input_shape[1], m.input_shape[2], m.input_shape[3]);
    }
    return ok();
  }

  Status table_prefix(const Section* s, uint32_t entry_bytes, uint32_t max_count, const char* what,
                      uint32_t* count) {
    APRT_ENSURE(s->size >= format::kTablePrefixBytes, Errc::kTruncated,
                "model_bin: %s table has no header", what);
    *count = load<uint32_t>(s->data);
    APRT_ENSURE(load<uint32_t>(s->data + 4) == entry_bytes, Errc::kBadHeader,
                "model_bin: %s entries are %u bytes, expected %u", what,
                load<uint32_t>(s->data + 4), entry_bytes);
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
    APRT_ENSURE(out.dtype == DType::kF32 && out.numel == 7, Errc::kBadGraph,
                "model_bin: output '%s' must be 7 f32 values (x y z qw qx qy qz), has %llu %s",
                out.name, static_cast<unsigned long long>(out.numel),
                format::dtype_name(out.dtype));
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
