// The model_bin reader refuses every corruption class with a distinct error,
// and never crashes (this suite also runs under ASan/UBSan).
#include "runtime/engine/model_file.h"

#include <gtest/gtest.h>

#include <cmath>
#include <cstring>

#include "runtime/engine/engine.h"
#include "tests/support/model_builder.h"

namespace aprt {
namespace {

using test::ModelBuilder;

Expected<ModelFile> parse(const std::vector<uint8_t>& b) {
  return ModelFile::parse(b.data(), b.size());
}

void expect_error(const std::vector<uint8_t>& b, Errc code, const char* fragment) {
  auto r = parse(b);
  ASSERT_FALSE(r) << "accepted a file that should fail with: " << fragment;
  EXPECT_EQ(r.error().code(), code) << r.error().message();
  EXPECT_NE(std::strstr(r.error().message(), fragment), nullptr) << r.error().message();
}

// Loading through the engine as well, so op-level validation runs.
void expect_load_error(const std::vector<uint8_t>& b, Errc code, const char* fragment) {
  auto r = Engine::load_memory(b.data(), b.size());
  ASSERT_FALSE(r) << "loaded a model that should fail with: " << fragment;
  EXPECT_EQ(r.error().code(), code) << r.error().message();
  EXPECT_NE(std::strstr(r.error().message(), fragment), nullptr) << r.error().message();
}

TEST(ModelFile, ParsesValidModel) {
  const auto b = test::make_small_model();
  auto r = parse(b);
  ASSERT_TRUE(r) << r.error().message();
  EXPECT_EQ(r->tensors().size(), 30u);
  EXPECT_EQ(r->ops().size(), 12u);
  EXPECT_EQ(r->meta().input_shape[1], 8u);
  EXPECT_STREQ(r->meta().producer, "model_builder (tests)");
}

TEST(ModelFile, RefusesEveryTruncation) {
  const auto b = test::make_small_model();
  // Every section boundary, and every 7th byte in between.
  std::vector<size_t> cuts{0, 1, 8, 63, 64, 65};
  for (const auto& s : test::sections_of(b)) {
    cuts.push_back(s.offset);
    cuts.push_back(s.offset + 1);
    cuts.push_back(s.offset + s.size - 1);
  }
  for (size_t c = 0; c < b.size(); c += 7) cuts.push_back(c);
  for (size_t cut : cuts) {
    if (cut >= b.size()) continue;
    std::vector<uint8_t> t(b.begin(), b.begin() + long(cut));
    auto r = parse(t);
    ASSERT_FALSE(r) << "accepted a file truncated to " << cut << " bytes";
    EXPECT_EQ(r.error().code(), Errc::kTruncated) << cut << ": " << r.error().message();
  }
}

TEST(ModelFile, RefusesFlippedBitsInEverySection) {
  const auto b = test::make_small_model();
  for (const auto& s : test::sections_of(b)) {
    if (s.size == 0) continue;
    for (uint64_t at : {s.offset, s.offset + s.size / 2, s.offset + s.size - 1}) {
      auto t = b;
      t[at] ^= 0x10;
      auto r = parse(t);
      ASSERT_FALSE(r) << "accepted a flipped bit at " << at;
      EXPECT_EQ(r.error().code(), Errc::kChecksum) << r.error().message();
      EXPECT_NE(std::strstr(r.error().message(), "checksum mismatch"), nullptr);
    }
  }
  // A flipped bit in the header or the section table.
  for (size_t at : {size_t(20), size_t(70), size_t(100)}) {
    auto t = b;
    t[at] ^= 0x01;
    EXPECT_FALSE(parse(t));
  }
}

TEST(ModelFile, RefusesBadMagicAndVersion) {
  auto b = test::make_small_model();
  b[0] = 'X';
  expect_error(b, Errc::kBadMagic, "bad magic");
  ModelBuilder mb;
  auto v2 = test::make_small_model([](ModelBuilder& m) { m.version_major = 2; });
  expect_error(v2, Errc::kUnsupportedVersion, "unsupported version 2.");
}

TEST(ModelFile, RefusesTrailingBytesAndWrongEndianness) {
  auto b = test::make_small_model();
  auto longer = b;
  longer.push_back(0);
  expect_error(longer, Errc::kBadHeader, "trailing data");
  auto t = b;
  uint32_t mark = 0x04030201;
  std::memcpy(t.data() + 28, &mark, 4);
  test::fix_checksums(t);
  expect_error(t, Errc::kBadHeader, "endianness");
}

// Flags and reserved fields must be 0 (FORMAT.md), each place its own message.
TEST(ModelFile, RefusesNonZeroReservedFields) {
  const auto b = test::make_small_model();
  auto poke = [&](size_t at, Errc code, const char* fragment) {
    auto t = b;
    t[at] ^= 0x01;
    test::fix_checksums(t);
    expect_error(t, code, fragment);
  };
  poke(32, Errc::kBadHeader, "header flags or reserved bytes are not 0");
  poke(63, Errc::kBadHeader, "header flags or reserved bytes are not 0");
  poke(64 + 4, Errc::kBadHeader, "flags or reserved field not 0");   // section 0 flags
  poke(64 + 28, Errc::kBadHeader, "flags or reserved field not 0");  // section 0 reserved
  const auto secs = test::sections_of(b);
  for (const auto& s : secs) {
    if (s.tag != format::kSecTensors) continue;
    poke(s.offset + 8, Errc::kBadHeader, "tensor table header: reserved words not 0");
    poke(s.offset + 16 + 7, Errc::kBadTensor, "tensor 0 'input': flags or reserved bytes not 0");
    poke(s.offset + 16 + 63, Errc::kBadTensor, "flags or reserved bytes not 0");
  }
}

// Metadata that parsed before and must not: norm_std first with a length of
// its own (the length check only ran when norm_mean came first), and pose
// bounds so wide that any decoded pose passed the bounds test as valid.
TEST(ModelFile, RefusesImplausibleMetadata) {
  expect_error(test::make_small_model([](ModelBuilder& m) {
                 m.norm_std = {0.229f};
                 m.norm_std_first = true;
               }),
               Errc::kBadMetadata, "3 norm_mean values but 1 norm_std values");
  expect_error(test::make_small_model([](ModelBuilder& m) {
                 m.norm_std = {0.2f, 0.2f};
               }),
               Errc::kBadMetadata, "3 norm_mean values but 2 norm_std values");
  expect_error(test::make_small_model([](ModelBuilder& m) {
                 m.norm_std = {0.2f, 0.0f, 0.2f};
                 m.norm_std_first = true;
               }),
               Errc::kBadMetadata, "norm_std[1] = 0 must be positive");
  expect_error(test::make_small_model([](ModelBuilder& m) {
                 m.pose_min = {-3e38f, 0, 0};
                 m.pose_max = {3e38f, 20, 5};
               }),
               Errc::kBadMetadata, "pose bounds axis 0 [-3e+38, 3e+38] m");
  expect_error(test::make_small_model([](ModelBuilder& m) {
                 m.pose_min = {0, -1e6f, 0};
                 m.pose_max = {10, 1e6f, 5};
               }),
               Errc::kBadMetadata, "an extent at most 1e+06 m");
  EXPECT_TRUE(parse(test::make_small_model([](ModelBuilder& m) {
    m.pose_min = {4.5e5f, 5.4e6f, 0};  // UTM coordinates
    m.pose_max = {4.6e5f, 5.5e6f, 100};
    m.norm_std_first = true;
  })));
}

TEST(ModelFile, RefusesSectionTableDefects) {
  const auto b = test::make_small_model();
  const auto secs = test::sections_of(b);
  {  // misaligned section offset
    auto t = b;
    uint64_t off = secs[2].offset + 4;
    std::memcpy(t.data() + 64 + 2 * 32 + 8, &off, 8);
    test::fix_checksums(t);
    expect_error(t, Errc::kMisaligned, "not 64-byte aligned");
  }
  {  // section past the end
    auto t = b;
    uint64_t size = b.size();
    std::memcpy(t.data() + 64 + 4 * 32 + 16, &size, 8);
    test::fix_checksums(t);
    expect_error(t, Errc::kSectionBounds, "outside");
  }
  {  // overlapping sections: TENS claims OPSQ's offset
    auto t = b;
    std::memcpy(t.data() + 64 + 2 * 32 + 8, &secs[3].offset, 8);
    test::fix_checksums(t);
    expect_error(t, Errc::kSectionBounds, "overlap");
  }
  {  // duplicated tag
    auto t = b;
    std::memcpy(t.data() + 64 + 1 * 32, &secs[0].tag, 4);
    test::fix_checksums(t);
    expect_error(t, Errc::kSectionBounds, "appears twice");
  }
  {  // missing section: rename WGHT
    auto t = b;
    uint32_t tag = format::fourcc('X', 'X', 'X', 'X');
    std::memcpy(t.data() + 64 + 4 * 32, &tag, 4);
    test::fix_checksums(t);
    expect_error(t, Errc::kSectionBounds, "WEIGHTS is missing");
  }
}

TEST(ModelFile, RefusesMissingMetadata) {
  auto b = test::make_small_model([](ModelBuilder& m) { m.with_producer = false; });
  expect_error(b, Errc::kBadMetadata, "'producer' is missing");
  auto bounds = test::make_small_model([](ModelBuilder& m) { m.pose_max = {0, 20, 5}; });
  expect_error(bounds, Errc::kBadMetadata, "pose bounds");
  auto heads = test::make_small_model([](ModelBuilder& m) { m.nheads = 3; });
  expect_error(heads, Errc::kBadMetadata, "multiple of nheads");
  auto modality = test::make_small_model([](ModelBuilder& m) { m.modality = 9; });
  expect_error(modality, Errc::kBadMetadata, "unknown modality");
}

TEST(ModelFile, RefusesInconsistentBevMetadata) {
  auto none = test::make_small_model([](ModelBuilder& m) { m.modality = 2; });
  expect_error(none, Errc::kBadMetadata, "needs metadata 'bev'");
  auto rgb = test::make_small_model([](ModelBuilder& m) {
    m.modality = 2;
    m.bev = {0.125f, -16, -16, -1.4f, 5};
  });
  expect_error(rgb, Errc::kBadMetadata, "square 2-channel grid, not 8x8x3");
  auto cell = test::make_small_model([](ModelBuilder& m) { m.bev = {0.0f, -16, -16, -1.4f, 5}; });
  expect_error(cell, Errc::kBadMetadata, "BEV cell size 0 m");
  auto clip = test::make_small_model([](ModelBuilder& m) { m.bev = {0.5f, -16, -16, -1.4f, 0}; });
  expect_error(clip, Errc::kBadMetadata, "BEV clip count 0");
  auto nan = test::make_small_model([](ModelBuilder& m) { m.bev = {0.5f, NAN, -16, -1.4f, 5}; });
  expect_error(nan, Errc::kBadMetadata, "bev");
  auto count = test::make_small_model([](ModelBuilder& m) { m.bev = {0.5f, -16, -16}; });
  expect_error(count, Errc::kBadMetadata, "META key 50 has 12 bytes");
}

// model_bin 1.3: confidence outputs (13 values) and their calibration go
// together; the scales are positive and bounded.
TEST(ModelFile, ConfidenceOutputsNeedTheirCalibration) {
  auto plain = test::make_small_model([](ModelBuilder& m) { m.uncertainty = {1.5f, 0.7f}; });
  expect_error(plain, Errc::kBadMetadata, "'uncertainty' without the confidence outputs");
  auto zero = test::make_small_model([](ModelBuilder& m) { m.uncertainty = {0.0f, 0.7f}; });
  expect_error(zero, Errc::kBadMetadata, "uncertainty calibration scales 0, 0.7");
  auto nan = test::make_small_model([](ModelBuilder& m) { m.uncertainty = {NAN, 0.7f}; });
  expect_error(nan, Errc::kBadMetadata, "uncertainty");
  auto count = test::make_small_model([](ModelBuilder& m) { m.uncertainty = {1.0f}; });
  expect_error(count, Errc::kBadMetadata, "META key 43 has 4 bytes");
}

// model_bin 1.4: the member count of an ensemble is read and reported; a
// record of the wrong size is refused like any other.
TEST(ModelFile, ReadsTheEnsembleMemberCount) {
  auto three = test::make_small_model([](ModelBuilder& m) { m.ensemble = {3}; });
  auto file = parse(three);
  ASSERT_TRUE(file) << file.error().message();
  EXPECT_EQ(file.value().meta().ensemble_members, 3u);
  // Its output has 7 values, not 13 per member: no member outputs
  // (FORMAT.md 1.5; golden.tiny_ensemble reads a file that has them).
  EXPECT_EQ(file.value().meta().member_outputs, 0u);
  auto plain = test::make_small_model([](ModelBuilder&) {});
  auto one = parse(plain);
  ASSERT_TRUE(one);
  EXPECT_EQ(one.value().meta().ensemble_members, 0u);
  auto count = test::make_small_model([](ModelBuilder& m) { m.ensemble = {3, 4}; });
  expect_error(count, Errc::kBadMetadata, "META key 44 has 8 bytes");
}

TEST(ModelFile, RefusesAbsurdShapes) {
  auto huge = test::make_small_model([](ModelBuilder& m) {
    m.set_dims(m.tensor_index("dw.out"), {1, 1 << 21, 4, 8});
  });
  expect_error(huge, Errc::kTooLarge, "dimension 1 is 2097152");
  auto many = test::make_small_model([](ModelBuilder& m) {
    m.set_dims(m.tensor_index("dw.out"), {1 << 19, 1 << 19, 4, 8});
  });
  expect_error(many, Errc::kTooLarge, "more than");
  auto zero = test::make_small_model([](ModelBuilder& m) {
    m.set_dims(m.tensor_index("dw.out"), {1, 0, 4, 8});
  });
  expect_error(zero, Errc::kTooLarge, "dimension 1 is 0");
  auto rank = test::make_small_model([](ModelBuilder& m) {
    m.set_dims(m.tensor_index("dw.out"), {1, 1, 1, 4, 8});
  });
  expect_error(rank, Errc::kBadTensor, "rank 5");
  auto data = test::make_small_model([](ModelBuilder& m) {
    m.set_dims(m.tensor_index("dw.w"), {3, 3, 9});
  });
  expect_error(data, Errc::kBadTensor, "stores 288 bytes, its shape needs 324");
}

TEST(ModelFile, RefusesBrokenGraphs) {
  auto before = test::make_small_model([](ModelBuilder& m) {
    m.set_inputs(m.op_index("stem"),
                 {m.tensor_index("input"), m.tensor_index("stem.w"), m.tensor_index("dw.out")});
  });
  expect_error(before, Errc::kBadGraph, "before anything writes it");
  auto index = test::make_small_model([](ModelBuilder& m) {
    m.set_inputs(m.op_index("stem"), {0, 9999, 2});
  });
  expect_error(index, Errc::kBadOp, "index 9999 invalid");
  auto write_const = test::make_small_model(
      [](ModelBuilder& m) { m.set_kind(m.tensor_index("stem.out"), format::TensorKind::kConst); });
  EXPECT_FALSE(parse(write_const));
}

// Found by the fuzzer: an absent (-1) weight input of a depthwise convolution
// reached the int8 check before the null check.
TEST(ModelFile, EngineRefusesAbsentWeights) {
  auto dw = test::make_small_model([](ModelBuilder& m) {
    m.set_inputs(m.op_index("dw"), {m.tensor_index("stem.out"), -1, m.tensor_index("dw.b")});
  });
  expect_load_error(dw, Errc::kBadOp, "op 1 'dw' (DWCONV2D): weights is missing");
  auto lin = test::make_small_model([](ModelBuilder& m) {
    m.set_inputs(m.op_index("proj"), {m.tensor_index("se.out"), -1, m.tensor_index("proj.b")});
  });
  expect_load_error(lin, Errc::kBadOp, "weights is missing");
  auto q = test::make_small_int8_model([](ModelBuilder& m) {
    m.set_inputs(m.op_index("proj"), {m.tensor_index("se.out"), m.tensor_index("proj.w.int8"), -1});
  });
  expect_load_error(q, Errc::kBadOp, "bias is missing");
}

TEST(ModelFile, EngineRefusesShapesInconsistentWithOps) {
  auto k = test::make_small_model([](ModelBuilder& m) {
    m.set_dims(m.tensor_index("proj.out"), {1, 4, 4, 15});
  });
  expect_load_error(k, Errc::kShapeMismatch, "op 3 'proj' (LINEAR)");
  auto conv = test::make_small_model([](ModelBuilder& m) {
    m.set_dims(m.tensor_index("stem.out"), {1, 5, 4, 8});
    m.set_dims(m.tensor_index("dw.out"), {1, 5, 4, 8});
    m.set_dims(m.tensor_index("se.out"), {1, 5, 4, 8});
  });
  expect_load_error(conv, Errc::kShapeMismatch, "the convolution gives 4x4");
  auto act =
      test::make_small_model([](ModelBuilder& m) { m.set_param(m.op_index("gelu"), 0, 99); });
  expect_load_error(act, Errc::kBadOp, "unknown activation 99");
  auto heads =
      test::make_small_model([](ModelBuilder& m) { m.set_param(m.op_index("attn"), 0, 3); });
  expect_load_error(heads, Errc::kBadOp, "3 heads do not divide the width 16");
  auto scores =
      test::make_small_model([](ModelBuilder& m) { m.set_param(m.op_index("attn"), 2, 3); });
  expect_load_error(scores, Errc::kBadOp, "precision 3 unknown (0 fp32, 1 int8 scores, 2 bf16)");
  auto pad = test::make_small_model([](ModelBuilder& m) { m.set_param(m.op_index("stem"), 2, 7); });
  expect_load_error(pad, Errc::kBadOp, "padding");
  auto eps = test::make_small_model(
      [](ModelBuilder& m) { m.set_param(m.op_index("ln"), 0, ModelBuilder::f32_bits(-1.0f)); });
  expect_load_error(eps, Errc::kBadOp, "epsilon");
}

}  // namespace
}  // namespace aprt
