// The model file's metadata section (model_bin/FORMAT.md, "Metadata"): every
// key's type and count checked, numbers finite, and what the modality needs
// present, before anything uses it.
#include <cmath>
#include <cstring>

#include "runtime/base/check.h"
#include "runtime/engine/model_bytes.h"

namespace aprt {

using format::MetaKey;
using format::MetaType;

Status parse_model_meta(const uint8_t* data, uint64_t size, ModelMeta* out) {
  ModelMeta& m = *out;
  uint64_t seen = 0;  // bit per known key index
  int std_channels = 0;
  auto mark = [&](int bit) { seen |= uint64_t(1) << bit; };
  uint64_t pos = 0;
  while (pos < size) {
    APRT_ENSURE(size - pos >= 8, Errc::kBadMetadata,
                "model_bin: META record header at byte %llu is cut off",
                static_cast<unsigned long long>(pos));
    const auto key = static_cast<MetaKey>(load<uint16_t>(data + pos));
    const auto type = static_cast<MetaType>(load<uint16_t>(data + pos + 2));
    const uint32_t len = load<uint32_t>(data + pos + 4);
    APRT_ENSURE(len <= size - pos - 8, Errc::kBadMetadata,
                "model_bin: META key %u claims %u bytes, past the section end", unsigned(key), len);
    const uint8_t* v = data + pos + 8;
    auto expect = [&](MetaType t, uint32_t min_count, uint32_t max_count) -> Status {
      APRT_ENSURE(type == t, Errc::kBadMetadata, "model_bin: META key %u has type %u, expected %u",
                  unsigned(key), unsigned(type), unsigned(t));
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
        std_channels = int(len / 4);  // compared with norm_mean's after the loop (any order)
        mark(5);
        break;
      case MetaKey::kResizePolicy: {
        if (!(st = expect(MetaType::kU32, 1, 1))) return st;
        const uint32_t r = load<uint32_t>(v);
        APRT_ENSURE(r == 1 || r == 2, Errc::kBadMetadata, "model_bin: unknown resize policy %u", r);
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
      case MetaKey::kDimFeedforward:
      case MetaKey::kEnsemble: {
        if (!(st = expect(MetaType::kU32, 1, 1))) return st;
        const uint32_t x = load<uint32_t>(v);
        APRT_ENSURE(x <= 65536, Errc::kBadMetadata, "model_bin: META key %u = %u is absurd",
                    unsigned(key), x);
        if (key == MetaKey::kDModel) m.d_model = x, mark(8);
        if (key == MetaKey::kNHeads) m.nheads = x, mark(9);
        if (key == MetaKey::kEncLayers) m.enc_layers = x, mark(10);
        if (key == MetaKey::kDecLayers) m.dec_layers = x, mark(11);
        if (key == MetaKey::kDimFeedforward) m.dim_feedforward = x;
        if (key == MetaKey::kEnsemble) m.ensemble_members = x;
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
      case MetaKey::kUncertainty: {
        if (!(st = expect(MetaType::kF32, 2, 2))) return st;
        float k[2] = {0.0f, 0.0f};
        if (!(st = f32s(k, 2, "uncertainty"))) return st;
        APRT_ENSURE(k[0] > 0.0f && k[0] <= 1e3f && k[1] > 0.0f && k[1] <= 1e3f, Errc::kBadMetadata,
                    "model_bin: uncertainty calibration scales %g, %g (each in (0, 1000])",
                    double(k[0]), double(k[1]));
        m.has_uncertainty = true;
        m.uncertainty_scale[0] = k[0];
        m.uncertainty_scale[1] = k[1];
        break;
      }
      case MetaKey::kConfigJson:
        if (!(st = expect(MetaType::kStr, 0, 1u << 20))) return st;
        m.config_json = reinterpret_cast<const char*>(v);
        m.config_json_bytes = len;
        break;
      case MetaKey::kBev: {
        if (!(st = expect(MetaType::kF32, 5, 5))) return st;
        float b[5] = {};  // GCC 12 -O3 cannot see f32s() fill it
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
  static const char* const kRequired[] = {"producer",  "source_sha256", "modality",   "input_shape",
                                          "norm_mean", "norm_std",      "pose_min",   "pose_max",
                                          "d_model",   "nheads",        "enc_layers", "dec_layers"};
  for (int bit = 0; bit < 12; ++bit) {
    APRT_ENSURE(seen & (uint64_t(1) << bit), Errc::kBadMetadata,
                "model_bin: required metadata '%s' is missing", kRequired[bit]);
  }
  APRT_ENSURE(std_channels == m.norm_channels, Errc::kBadMetadata,
              "model_bin: %d norm_mean values but %d norm_std values", m.norm_channels,
              std_channels);
  for (int i = 0; i < 3; ++i) {
    APRT_ENSURE(m.pose_min[i] < m.pose_max[i], Errc::kBadMetadata,
                "model_bin: pose bounds axis %d: min %g >= max %g", i, m.pose_min[i],
                m.pose_max[i]);
    // A map frame's coordinates (UTM northings reach 1e7 m) and a map's
    // extent: beyond these a bound is corrupt, and poses decoded from it
    // would go out as valid (the bounds test passes anything inside them).
    APRT_ENSURE(std::fabs(m.pose_min[i]) <= format::kMaxPoseCoordinate &&
                    std::fabs(m.pose_max[i]) <= format::kMaxPoseCoordinate &&
                    m.pose_max[i] - m.pose_min[i] <= format::kMaxPoseExtent,
                Errc::kBadMetadata,
                "model_bin: pose bounds axis %d [%g, %g] m: coordinates at most %g m, an extent "
                "at most %g m",
                i, m.pose_min[i], m.pose_max[i], double(format::kMaxPoseCoordinate),
                double(format::kMaxPoseExtent));
  }
  APRT_ENSURE(m.nheads > 0 && m.d_model > 0 && m.d_model % m.nheads == 0, Errc::kBadMetadata,
              "model_bin: d_model %u is not a positive multiple of nheads %u", m.d_model, m.nheads);
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

}  // namespace aprt
