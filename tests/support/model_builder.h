// Builds small model_bin files in memory for tests, and edits existing ones.
//
// Independent of the Python writer on purpose: two writers that agree on the
// format (tests/tools checks the Python side) are a check on FORMAT.md itself.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "runtime/engine/model_format.h"

namespace aprt::test {

class ModelBuilder {
 public:
  ModelBuilder();

  int constant(const std::string& name, std::vector<int> dims, std::vector<float> data);
  // An int8 constant (weights [N, K]) with a per-tensor scale (> 0) or, when
  // `scale` is 0, per-channel scales in the f32 constant `qscale`.
  int constant_i8(const std::string& name, std::vector<int> dims, std::vector<int8_t> data,
                  float scale, int qscale = -1);
  int activation(const std::string& name, std::vector<int> dims);
  int input(const std::string& name, std::vector<int> dims);
  int output(const std::string& name, std::vector<int> dims);
  void op(format::OpCode code, const std::string& name, std::vector<int> inputs,
          std::vector<int> outputs, std::vector<int32_t> params = {});
  static int32_t f32_bits(float f);

  // Edits for tests that need an invalid but well-formed model.
  int tensor_index(const std::string& name) const;
  int op_index(const std::string& name) const;
  void set_dims(int tensor, std::vector<int> dims) { tensors_[tensor].dims = std::move(dims); }
  void set_param(int op, int k, int32_t v);
  void set_inputs(int op, std::vector<int> inputs) { ops_[op].in = std::move(inputs); }
  void set_kind(int tensor, format::TensorKind kind) { tensors_[tensor].kind = kind; }
  void set_quant(int tensor, float scale, int32_t zero, int qscale) {
    tensors_[tensor].scale = scale;
    tensors_[tensor].zero = zero;
    tensors_[tensor].qscale = qscale;
  }
  void set_data(int tensor, std::vector<float> data) { tensors_[tensor].data = std::move(data); }

  // Metadata (sensible defaults; the input shape is taken from the input tensor).
  uint32_t modality = 1;
  std::vector<float> bev;     // META 'bev' (cell, x_min, y_min, threshold, clip) when not empty
  std::vector<float> points;  // META 'points' (crop radius, coordinate scale) when not empty
  std::vector<float> uncertainty;  // META 'uncertainty' (position, rotation scales) when not empty
  std::vector<uint32_t> ensemble;  // META 'ensemble' (member count) when not empty
  std::vector<float> pose_min{0, 0, 0}, pose_max{10, 20, 5};
  std::vector<float> norm_std;  // META 'norm_std' when not empty (else 0.25 per channel)
  bool norm_std_first = false;  // write norm_std before norm_mean
  uint32_t d_model = 16, nheads = 2, enc_layers = 1, dec_layers = 1;
  uint16_t version_major = format::kVersionMajor;
  bool with_producer = true;

  std::vector<uint8_t> build() const;

 private:
  struct T {
    std::string name;
    std::vector<int> dims;
    format::TensorKind kind;
    std::vector<float> data;
    format::DType dtype = format::DType::kF32;
    std::vector<int8_t> i8;
    float scale = 0.0f;
    int32_t zero = 0;
    int qscale = -1;
  };
  struct O {
    format::OpCode code;
    std::string name;
    std::vector<int> in, out;
    std::vector<int32_t> params;
  };
  std::vector<T> tensors_;
  std::vector<O> ops_;
};

// A small model that uses every op kind: input [1,8,8,3] -> pose [1,7].
std::vector<uint8_t> make_small_model();
// Same with a modification applied to the builder before writing.
std::vector<uint8_t> make_small_model(void (*edit)(ModelBuilder&));
// The small model with its pointwise LINEAR "proj" (64 rows, 8 -> 16) in int8:
// weights "proj.w.int8" with per-channel scales "proj.w.qscale", input scale
// 0.02, zero point 100.
std::vector<uint8_t> make_small_int8_model(void (*edit)(ModelBuilder&) = nullptr);
// A small raw-points model (modality 3) using every point op: input
// [1, 64, 1, 6] -> FPS 16 -> ball group -> MLP -> max -> FPS 4 -> ball group
// -> max -> 3-NN interpolation back to 16 ++ skip -> 2 x 2 x 2 grid tokens ->
// projection -> attention pooling -> pose [1, 7].
std::vector<uint8_t> make_small_points_model(void (*edit)(ModelBuilder&) = nullptr);
// The same with a pose head that answers unit quaternions, so its estimates
// pass the sanity checks and reach DDS (the loop and peer tests).
std::vector<uint8_t> make_sane_small_points_model();

struct SectionInfo {
  uint32_t tag;
  uint64_t offset;
  uint64_t size;
};
std::vector<SectionInfo> sections_of(const std::vector<uint8_t>& file);
// Recomputes the header and section checksums after a deliberate edit.
void fix_checksums(std::vector<uint8_t>& file);

}  // namespace aprt::test
