#include "tests/support/model_builder.h"

#include <cstring>
#include <random>

#include "runtime/base/crc32.h"

namespace aprt::test {
namespace {

using format::OpCode;

void put(std::vector<uint8_t>& b, const void* p, size_t n) {
  const auto* c = static_cast<const uint8_t*>(p);
  b.insert(b.end(), c, c + n);
}
template <class V>
void put(std::vector<uint8_t>& b, V v) {
  put(b, &v, sizeof v);
}
void pad_to(std::vector<uint8_t>& b, size_t align) {
  while (b.size() % align) b.push_back(0);
}

void meta_record(std::vector<uint8_t>& b, uint16_t key, uint16_t type, const void* p, uint32_t n) {
  put(b, key);
  put(b, type);
  put(b, n);
  put(b, p, n);
  pad_to(b, 4);
}

}  // namespace

ModelBuilder::ModelBuilder() = default;

int ModelBuilder::constant(const std::string& name, std::vector<int> dims,
                           std::vector<float> data) {
  tensors_.push_back(T{name,
                       std::move(dims),
                       format::TensorKind::kConst,
                       std::move(data),
                       format::DType::kF32,
                       {},
                       0.0f,
                       0,
                       -1});
  return int(tensors_.size()) - 1;
}
int ModelBuilder::activation(const std::string& name, std::vector<int> dims) {
  tensors_.push_back(T{name,
                       std::move(dims),
                       format::TensorKind::kActivation,
                       {},
                       format::DType::kF32,
                       {},
                       0.0f,
                       0,
                       -1});
  return int(tensors_.size()) - 1;
}
int ModelBuilder::input(const std::string& name, std::vector<int> dims) {
  tensors_.push_back(T{
      name, std::move(dims), format::TensorKind::kInput, {}, format::DType::kF32, {}, 0.0f, 0, -1});
  return int(tensors_.size()) - 1;
}
int ModelBuilder::output(const std::string& name, std::vector<int> dims) {
  tensors_.push_back(T{name,
                       std::move(dims),
                       format::TensorKind::kOutput,
                       {},
                       format::DType::kF32,
                       {},
                       0.0f,
                       0,
                       -1});
  return int(tensors_.size()) - 1;
}
void ModelBuilder::op(OpCode code, const std::string& name, std::vector<int> inputs,
                      std::vector<int> outputs, std::vector<int32_t> params) {
  ops_.push_back({code, name, std::move(inputs), std::move(outputs), std::move(params)});
}
int32_t ModelBuilder::f32_bits(float f) {
  int32_t i;
  std::memcpy(&i, &f, 4);
  return i;
}

int ModelBuilder::tensor_index(const std::string& name) const {
  for (size_t i = 0; i < tensors_.size(); ++i) {
    if (tensors_[i].name == name) return int(i);
  }
  return -1;
}
int ModelBuilder::op_index(const std::string& name) const {
  for (size_t i = 0; i < ops_.size(); ++i) {
    if (ops_[i].name == name) return int(i);
  }
  return -1;
}
void ModelBuilder::set_param(int op, int k, int32_t v) {
  if (ops_[op].params.size() <= size_t(k)) ops_[op].params.resize(size_t(k) + 1, 0);
  ops_[op].params[size_t(k)] = v;
}

std::vector<uint8_t> ModelBuilder::build() const {
  std::vector<uint8_t> strings{0};
  auto str = [&](const std::string& s) {
    const uint32_t off = uint32_t(strings.size());
    put(strings, s.data(), s.size());
    strings.push_back(0);
    return off;
  };
  // META
  std::vector<uint8_t> meta;
  const T* in = nullptr;
  for (const T& t : tensors_) {
    if (t.kind == format::TensorKind::kInput) in = &t;
  }
  const std::string producer = "model_builder (tests)";
  if (with_producer) meta_record(meta, 1, 3, producer.data(), uint32_t(producer.size()));
  uint8_t sha[32];
  for (int i = 0; i < 32; ++i) sha[i] = uint8_t(i);
  meta_record(meta, 2, 4, sha, 32);
  meta_record(meta, 10, 1, &modality, 4);
  uint32_t shape[4] = {1, 1, 1, 1};
  if (in) {
    for (size_t d = 0; d < 4 && d < in->dims.size(); ++d) shape[d] = uint32_t(in->dims[d]);
  }
  meta_record(meta, 11, 1, shape, 16);
  std::vector<float> mean(shape[3], 0.5f), stdev(shape[3], 0.25f);
  if (!norm_std.empty()) stdev = norm_std;
  if (norm_std_first) meta_record(meta, 13, 2, stdev.data(), uint32_t(stdev.size() * 4));
  meta_record(meta, 12, 2, mean.data(), uint32_t(mean.size() * 4));
  if (!norm_std_first) meta_record(meta, 13, 2, stdev.data(), uint32_t(stdev.size() * 4));
  meta_record(meta, 20, 2, pose_min.data(), uint32_t(pose_min.size() * 4));
  meta_record(meta, 21, 2, pose_max.data(), uint32_t(pose_max.size() * 4));
  if (!bev.empty()) meta_record(meta, 50, 2, bev.data(), uint32_t(bev.size() * 4));
  if (!points.empty()) meta_record(meta, 51, 2, points.data(), uint32_t(points.size() * 4));
  if (!uncertainty.empty()) {
    meta_record(meta, 43, 2, uncertainty.data(), uint32_t(uncertainty.size() * 4));
  }
  if (!ensemble.empty()) meta_record(meta, 44, 1, ensemble.data(), uint32_t(ensemble.size() * 4));
  meta_record(meta, 31, 1, &d_model, 4);
  meta_record(meta, 32, 1, &nheads, 4);
  meta_record(meta, 33, 1, &enc_layers, 4);
  meta_record(meta, 34, 1, &dec_layers, 4);
  // TENS + WGHT
  std::vector<uint8_t> tens, weights;
  put(tens, uint32_t(tensors_.size()));
  put(tens, format::kTensorEntryBytes);
  put(tens, uint64_t(0));
  for (const T& t : tensors_) {
    put(tens, str(t.name));
    tens.push_back(uint8_t(t.dtype));
    tens.push_back(uint8_t(t.dims.size()));
    tens.push_back(uint8_t(t.kind));
    tens.push_back(0);
    for (size_t d = 0; d < 4; ++d) put(tens, uint32_t(d < t.dims.size() ? t.dims[d] : 0));
    uint64_t off = 0, bytes = 0;
    if (t.kind == format::TensorKind::kConst) {
      pad_to(weights, format::kAlign);
      off = weights.size();
      if (t.dtype == format::DType::kI8) {
        bytes = t.i8.size();
        put(weights, t.i8.data(), bytes);
      } else {
        bytes = t.data.size() * 4;
        put(weights, t.data.data(), bytes);
      }
    }
    put(tens, off);
    put(tens, bytes);
    put(tens, t.scale);
    put(tens, t.zero);
    put(tens, int32_t(t.qscale));
    for (int r = 0; r < 3; ++r) put(tens, uint32_t(0));
  }
  // OPSQ
  std::vector<uint8_t> ops;
  put(ops, uint32_t(ops_.size()));
  put(ops, format::kOpEntryBytes);
  put(ops, uint64_t(0));
  for (const O& o : ops_) {
    put(ops, uint16_t(o.code));
    ops.push_back(uint8_t(o.in.size()));
    ops.push_back(uint8_t(o.out.size()));
    put(ops, str(o.name));
    for (int k = 0; k < 8; ++k) put(ops, int32_t(k < int(o.in.size()) ? o.in[k] : -1));
    for (int k = 0; k < 2; ++k) put(ops, int32_t(k < int(o.out.size()) ? o.out[k] : -1));
    for (int k = 0; k < 12; ++k) put(ops, int32_t(k < int(o.params.size()) ? o.params[k] : 0));
  }
  const std::vector<std::pair<uint32_t, const std::vector<uint8_t>*>> secs = {
      {format::kSecMeta, &meta},
      {format::kSecStrings, &strings},
      {format::kSecTensors, &tens},
      {format::kSecOps, &ops},
      {format::kSecWeights, &weights}};
  std::vector<uint8_t> file(format::kHeaderBytes + secs.size() * format::kSectionEntryBytes, 0);
  std::vector<SectionInfo> placed;
  for (const auto& [tag, blob] : secs) {
    pad_to(file, format::kAlign);
    placed.push_back({tag, file.size(), blob->size()});
    put(file, blob->data(), blob->size());
  }
  uint8_t* h = file.data();
  std::memcpy(h, format::kMagic, 8);
  const uint16_t minor = format::kVersionMinor;
  const uint32_t hb = format::kHeaderBytes, count = uint32_t(secs.size()),
                 endian = format::kEndianMark;
  const uint64_t total = file.size();
  std::memcpy(h + 8, &version_major, 2);
  std::memcpy(h + 10, &minor, 2);
  std::memcpy(h + 12, &hb, 4);
  std::memcpy(h + 16, &total, 8);
  std::memcpy(h + 24, &count, 4);
  std::memcpy(h + 28, &endian, 4);
  for (size_t i = 0; i < placed.size(); ++i) {
    uint8_t* e = h + format::kHeaderBytes + i * format::kSectionEntryBytes;
    std::memcpy(e, &placed[i].tag, 4);
    std::memcpy(e + 8, &placed[i].offset, 8);
    std::memcpy(e + 16, &placed[i].size, 8);
  }
  fix_checksums(file);
  return file;
}

std::vector<SectionInfo> sections_of(const std::vector<uint8_t>& file) {
  std::vector<SectionInfo> out;
  uint32_t count;
  std::memcpy(&count, file.data() + 24, 4);
  for (uint32_t i = 0; i < count; ++i) {
    const uint8_t* e = file.data() + format::kHeaderBytes + i * format::kSectionEntryBytes;
    SectionInfo s;
    std::memcpy(&s.tag, e, 4);
    std::memcpy(&s.offset, e + 8, 8);
    std::memcpy(&s.size, e + 16, 8);
    out.push_back(s);
  }
  return out;
}

void fix_checksums(std::vector<uint8_t>& file) {
  uint32_t count;
  std::memcpy(&count, file.data() + 24, 4);
  const auto secs = sections_of(file);
  for (uint32_t i = 0; i < count; ++i) {
    const SectionInfo& s = secs[i];
    if (s.offset > file.size() || s.size > file.size() - s.offset) continue;
    const uint32_t crc = crc32(file.data() + s.offset, s.size);
    std::memcpy(file.data() + format::kHeaderBytes + i * format::kSectionEntryBytes + 24, &crc, 4);
  }
  std::memset(file.data() + 36, 0, 4);
  const uint32_t crc =
      crc32(file.data(), format::kHeaderBytes + count * format::kSectionEntryBytes);
  std::memcpy(file.data() + 36, &crc, 4);
}

namespace {

std::vector<float> random_values(size_t n, uint32_t seed, float scale) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<float> u(-scale, scale);
  std::vector<float> v(n);
  for (float& x : v) x = u(rng);
  return v;
}

void build_small(ModelBuilder& b) {
  using format::OpCode;
  const int x = b.input("input", {1, 8, 8, 3});
  // stem: 3x3 stride 2, TF-same padding (0,0,1,1) -> [1,4,4,8], SiLU
  const int w0 = b.constant("stem.w", {8, 3, 3, 3}, random_values(8 * 27, 1, 0.5f));
  const int b0 = b.constant("stem.b", {8}, random_values(8, 2, 0.1f));
  const int y0 = b.activation("stem.out", {1, 4, 4, 8});
  b.op(OpCode::kConv2d, "stem", {x, w0, b0}, {y0}, {2, 2, 0, 0, 1, 1, 1});
  // depthwise 3x3, pads 1
  const int w1 = b.constant("dw.w", {3, 3, 8}, random_values(72, 3, 0.5f));
  const int b1 = b.constant("dw.b", {8}, random_values(8, 4, 0.1f));
  const int y1 = b.activation("dw.out", {1, 4, 4, 8});
  b.op(OpCode::kDwConv2d, "dw", {y0, w1, b1}, {y1}, {1, 1, 1, 1, 1, 1, 1});
  // squeeze-excite 8 -> 2 -> 8
  const int s1 = b.constant("se.w1", {2, 8}, random_values(16, 5, 0.5f));
  const int s2 = b.constant("se.b1", {2}, random_values(2, 6, 0.1f));
  const int s3 = b.constant("se.w2", {8, 2}, random_values(16, 7, 0.5f));
  const int s4 = b.constant("se.b2", {8}, random_values(8, 8, 0.1f));
  const int y2 = b.activation("se.out", {1, 4, 4, 8});
  b.op(OpCode::kSqueezeExcite, "se", {y1, s1, s2, s3, s4}, {y2});
  // pointwise 8 -> 16 (LINEAR on the map)
  const int w3 = b.constant("proj.w", {16, 8}, random_values(128, 9, 0.5f));
  const int b3 = b.constant("proj.b", {16}, random_values(16, 10, 0.1f));
  const int y3 = b.activation("proj.out", {1, 4, 4, 16});
  b.op(OpCode::kLinear, "proj", {y2, w3, b3}, {y3}, {0});
  const int g = b.constant("ln.g", {16}, random_values(16, 11, 1.0f));
  const int be = b.constant("ln.b", {16}, random_values(16, 12, 0.1f));
  const int y4 = b.activation("ln.out", {16, 16});
  b.op(OpCode::kLayerNorm, "ln", {y3, g, be}, {y4}, {ModelBuilder::f32_bits(1e-5f)});
  const int y5 = b.activation("attn.out", {16, 16});
  b.op(OpCode::kAttention, "attn", {y4, y4, y4}, {y5}, {2, ModelBuilder::f32_bits(0.35f)});
  const int y6 = b.activation("res.out", {16, 16});
  b.op(OpCode::kAdd, "res", {y5, y4}, {y6});
  const int y7 = b.activation("gelu.out", {16, 16});
  b.op(OpCode::kActivation, "gelu", {y6}, {y7}, {2});
  const int q = b.constant("query", {1, 16}, random_values(16, 13, 1.0f));
  const int y8 = b.activation("pool.out", {1, 16});
  b.op(OpCode::kAttention, "pool", {q, y7, y7}, {y8}, {2, ModelBuilder::f32_bits(0.35f)});
  const int wt = b.constant("head_t.w", {3, 16}, random_values(48, 14, 0.5f));
  const int bt = b.constant("head_t.b", {3}, random_values(3, 15, 0.1f));
  const int yt = b.activation("head_t.out", {1, 3});
  b.op(OpCode::kLinear, "head_t", {y8, wt, bt}, {yt}, {0});
  const int wr = b.constant("head_r.w", {4, 16}, random_values(64, 16, 0.5f));
  const int br = b.constant("head_r.b", {4}, random_values(4, 17, 0.1f));
  const int yr = b.activation("head_r.out", {1, 4});
  b.op(OpCode::kLinear, "head_r", {y8, wr, br}, {yr}, {0});
  const int out = b.output("pose", {1, 7});
  b.op(OpCode::kConcat, "pose", {yt, yr}, {out});
}

void build_small_points(ModelBuilder& b) {
  using format::OpCode;
  b.modality = 3;
  b.points = {20.0f, 20.0f};
  const int x = b.input("input", {1, 64, 1, 6});
  const int c1 = b.activation("fps1.out", {1, 16, 1, 3});
  b.op(OpCode::kFps, "fps1", {x}, {c1});
  const int g1 = b.activation("group1.out", {1, 16, 4, 9});
  b.op(OpCode::kBallGroup, "group1", {x, c1, x}, {g1}, {ModelBuilder::f32_bits(0.5f)});
  const int w1 = b.constant("mlp1.w", {8, 9}, random_values(72, 21, 0.5f));
  const int b1 = b.constant("mlp1.b", {8}, random_values(8, 22, 0.1f));
  const int m1 = b.activation("mlp1.out", {1, 16, 4, 8});
  b.op(OpCode::kLinear, "mlp1", {g1, w1, b1}, {m1}, {4});
  const int f1 = b.activation("max1.out", {1, 16, 1, 8});
  b.op(OpCode::kGroupMax, "max1", {m1}, {f1});
  const int c2 = b.activation("fps2.out", {1, 4, 1, 3});
  b.op(OpCode::kFps, "fps2", {c1}, {c2});
  const int g2 = b.activation("group2.out", {1, 4, 4, 11});
  b.op(OpCode::kBallGroup, "group2", {c1, c2, f1}, {g2}, {ModelBuilder::f32_bits(1.0f)});
  const int f2 = b.activation("max2.out", {1, 4, 1, 11});
  b.op(OpCode::kGroupMax, "max2", {g2}, {f2});
  const int up = b.activation("interp.out", {1, 16, 1, 11});
  b.op(OpCode::kThreeInterp, "interp", {c1, c2, f2}, {up});
  const int cat = b.activation("cat.out", {1, 16, 1, 19});
  b.op(OpCode::kConcat, "cat", {up, f1}, {cat});
  const int tok = b.activation("tokens.out", {1, 2, 4, 19});
  b.op(OpCode::kGridTokens, "tokens", {c1, cat}, {tok}, {2, 2, 2});
  const int wp = b.constant("proj.w", {16, 19}, random_values(16 * 19, 23, 0.5f));
  const int bp = b.constant("proj.b", {16}, random_values(16, 24, 0.1f));
  const int pr = b.activation("proj.out", {8, 16});
  b.op(OpCode::kLinear, "proj", {tok, wp, bp}, {pr}, {0});
  const int q = b.constant("query", {1, 16}, random_values(16, 25, 1.0f));
  const int pool = b.activation("pool.out", {1, 16});
  b.op(OpCode::kAttention, "pool", {q, pr, pr}, {pool}, {2, ModelBuilder::f32_bits(0.35f)});
  const int wt = b.constant("head_t.w", {3, 16}, random_values(48, 26, 0.5f));
  const int bt = b.constant("head_t.b", {3}, random_values(3, 27, 0.1f));
  const int yt = b.activation("head_t.out", {1, 3});
  b.op(OpCode::kLinear, "head_t", {pool, wt, bt}, {yt}, {0});
  const int wr = b.constant("head_r.w", {4, 16}, random_values(64, 28, 0.5f));
  const int br = b.constant("head_r.b", {4}, random_values(4, 29, 0.1f));
  const int yr = b.activation("head_r.out", {1, 4});
  b.op(OpCode::kLinear, "head_r", {pool, wr, br}, {yr}, {0});
  const int out = b.output("pose", {1, 7});
  b.op(OpCode::kConcat, "pose", {yt, yr}, {out});
}

}  // namespace

std::vector<uint8_t> make_small_points_model(void (*edit)(ModelBuilder&)) {
  ModelBuilder b;
  build_small_points(b);
  if (edit) edit(b);
  return b.build();
}

std::vector<uint8_t> make_sane_small_points_model() {
  return make_small_points_model([](ModelBuilder& m) {
    m.set_data(m.tensor_index("head_r.w"), std::vector<float>(64, 0.001f));
    m.set_data(m.tensor_index("head_r.b"), {1.0f, 0.0f, 0.0f, 0.0f});
  });
}

std::vector<uint8_t> make_small_model() {
  return make_small_model(nullptr);
}

int ModelBuilder::constant_i8(const std::string& name, std::vector<int> dims,
                              std::vector<int8_t> data, float scale, int qscale) {
  T t{name, std::move(dims), format::TensorKind::kConst, {}, format::DType::kI8, {}, 0.0f, 0, -1};
  t.dtype = format::DType::kI8;
  t.i8 = std::move(data);
  t.scale = scale;
  t.qscale = qscale;
  tensors_.push_back(std::move(t));
  return int(tensors_.size()) - 1;
}

std::vector<uint8_t> make_small_int8_model(void (*edit)(ModelBuilder&)) {
  ModelBuilder b;
  build_small(b);
  const int op = b.op_index("proj");
  std::vector<float> scales(16);
  std::vector<int8_t> w(16 * 8);
  for (int j = 0; j < 16; ++j) scales[j] = 0.004f + 0.0005f * float(j);
  for (size_t i = 0; i < w.size(); ++i) w[i] = int8_t(int((i * 37 + 11) % 255) - 127);
  const int qs = b.constant("proj.w.qscale", {16}, scales);
  const int wq = b.constant_i8("proj.w.int8", {16, 8}, w, 0.0f, qs);
  b.set_inputs(op, {b.tensor_index("se.out"), wq, b.tensor_index("proj.b")});
  b.set_param(op, 1, ModelBuilder::f32_bits(0.02f));
  b.set_param(op, 2, 100);
  if (edit) edit(b);
  return b.build();
}

std::vector<uint8_t> make_small_model(void (*edit)(ModelBuilder&)) {
  ModelBuilder b;
  build_small(b);
  if (edit) edit(b);
  return b.build();
}

}  // namespace aprt::test
