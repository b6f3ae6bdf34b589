// A parsed and validated model_bin image (model_bin/FORMAT.md).
//
// ModelFile::parse() checks everything that can be checked without knowing
// what an op computes: header, version, section table, checksums, metadata,
// the tensor table, op records and the graph's order (every tensor defined
// once, before it is read). Op-specific shape rules are checked by each op's
// prepare() in the engine. Each refusal names the check that failed.
//
// The ModelFile points into the bytes it was parsed from; they must outlive it.
#pragma once

#include <cstddef>
#include <cstdint>
#include <vector>

#include "runtime/base/expected.h"
#include "runtime/engine/model_format.h"

namespace aprt {

struct ModelMeta {
  static constexpr int kMaxChannels = 8;  // input channels with a normalisation
  char producer[64] = {};
  uint8_t source_sha256[32] = {};
  char source_name[128] = {};
  format::Modality modality = format::Modality::kImage;
  uint32_t input_shape[4] = {};  // N, H, W, C
  int norm_channels = 0;
  float norm_mean[kMaxChannels] = {};
  float norm_std[kMaxChannels] = {};
  format::ResizePolicy resize_policy = format::ResizePolicy::kShorterThenCenterCrop;
  float pose_min[3] = {};
  float pose_max[3] = {};
  char backbone[32] = {};
  uint32_t d_model = 0, nheads = 0, enc_layers = 0, dec_layers = 0, dim_feedforward = 0;
  bool has_val_error = false;
  float val_error_position_m = 0.0f;
  float val_error_orientation_deg = 0.0f;
  // Per-pose confidence (1.3): the network's outputs 7..12 are the log
  // Laplace scales of its position (normalised units, per map axis) and
  // rotation (radians, per camera axis) errors; sigma = scale * sqrt(2) *
  // exp(output) with these calibration scales (position, rotation), fitted on
  // the validation drive so that the 95 % regions hold 95 % of its errors.
  bool has_uncertainty = false;
  float uncertainty_scale[2] = {0.0f, 0.0f};
  // 1.4: how many networks the graph averages (aprt_tools ensemble); 0 for
  // one network. The graph itself does the averaging.
  uint32_t ensemble_members = 0;
  // 1.5: the output is each member's 13 outputs side by side (under this
  // file's bounds), merged by decode_pose (ensemble_merge.h):
  // ensemble_members when it is, else 0 (a 1.4 file whose graph averages;
  // set by the loader from the output's size).
  uint32_t member_outputs = 0;
  const char* config_json = nullptr;  // points into the file; not NUL-terminated
  size_t config_json_bytes = 0;
  // How the file was quantised (method, calibration set, per-op policy) as
  // JSON; null for fp32 files. Informational: the policy itself is the dtype
  // of each op's weights.
  const char* quantization = nullptr;
  size_t quantization_bytes = 0;
  // LiDAR BEV models (modality 2): the histogram's geometry (docs/lidar.md);
  // the grid is the input's H = W.
  bool has_bev = false;
  float bev_cell_m = 0.0f, bev_x_min = 0.0f, bev_y_min = 0.0f;
  float bev_height_threshold_m = 0.0f, bev_clip_count = 0.0f;
  // LiDAR points models (modality 3): the crop and the coordinate scale of the
  // features (docs/lidar.md); the sample count is the input's H.
  bool has_points = false;
  float points_crop_radius_m = 0.0f, points_coord_scale_m = 0.0f;
};

struct TensorEntry {
  const char* name = "";
  format::DType dtype = format::DType::kF32;
  format::TensorKind kind = format::TensorKind::kActivation;
  int rank = 0;
  uint32_t dims[format::kMaxRank] = {};
  uint64_t numel = 0;
  uint64_t bytes = 0;
  uint64_t data_offset = 0;  // within WGHT, constants only
  float scale = 0.0f;        // per-tensor quantisation; 0 = not quantised
  int32_t zero_point = 0;
  int32_t qscale_tensor = -1;  // per-channel scales (f32 constant), or -1
};

struct OpEntry {
  format::OpCode code = format::OpCode::kAdd;
  const char* name = "";
  int n_in = 0;
  int n_out = 0;
  int32_t in[format::kMaxOpInputs] = {};
  int32_t out[format::kMaxOpOutputs] = {};
  int32_t params[format::kMaxOpParams] = {};
};

struct ParseOptions {
  bool verify_checksums = true;
  // For a loader that does not hold the weights in `data` (Engine::load_file
  // reads them from the file piece by piece): section_crc computes a
  // section's checksum from the file (offset and size in it), fetch puts
  // bytes of the file into `data` before parse() reads them (the per-channel
  // scales it checks). False: the file could not be read.
  bool (*section_crc)(void* source, uint64_t offset, uint64_t size, uint32_t* crc) = nullptr;
  bool (*fetch)(void* source, uint64_t offset, uint64_t size) = nullptr;
  void* source = nullptr;
};

class ModelFile {
 public:
  static Expected<ModelFile> parse(const uint8_t* data, size_t size,
                                   const ParseOptions& options = {});

  const ModelMeta& meta() const { return meta_; }
  const std::vector<TensorEntry>& tensors() const { return tensors_; }
  const std::vector<OpEntry>& ops() const { return ops_; }
  // The WEIGHTS section (null after relocate_tables()), its size and offset.
  const uint8_t* weights() const { return weights_; }
  uint64_t weights_bytes() const { return weights_bytes_; }
  uint64_t weights_offset() const { return weights_offset_; }
  // The file's bytes without the WEIGHTS section ([0, weights_offset) then
  // what follows the section), which every name and string points into.
  uint64_t tables_bytes() const { return file_bytes_ - weights_bytes_; }
  // The engine keeps the tables, not the file: after it copied them to
  // `tables` (tables_bytes() bytes, as above), every name and metadata string
  // points there instead of into `file`; weights() is null from then on.
  void relocate_tables(const uint8_t* file, const uint8_t* tables);
  uint64_t file_bytes() const { return file_bytes_; }
  uint16_t version_major() const { return version_major_; }
  uint16_t version_minor() const { return version_minor_; }
  int input_index() const { return input_; }
  int output_index() const { return output_; }

 private:
  ModelMeta meta_;
  std::vector<TensorEntry> tensors_;
  std::vector<OpEntry> ops_;
  const uint8_t* weights_ = nullptr;
  uint64_t weights_bytes_ = 0;
  uint64_t weights_offset_ = 0;
  uint64_t file_bytes_ = 0;
  uint16_t version_major_ = 0;
  uint16_t version_minor_ = 0;
  int input_ = -1;
  int output_ = -1;

  friend class ModelFileParser;
};

}  // namespace aprt
