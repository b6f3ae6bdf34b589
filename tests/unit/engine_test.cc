#include "runtime/engine/engine.h"

#include <gtest/gtest.h>
#include <unistd.h>

#include <cmath>
#include <cstdlib>
#include <cstring>
#include <string>
#include <vector>

#include "runtime/base/allocation_counter.h"
#include "tests/support/model_builder.h"

namespace aprt {
namespace {

void fill_input(Engine& e) {
  for (size_t i = 0; i < e.input().numel; ++i) e.input().f32()[i] = std::sin(0.37f * float(i));
}

TEST(Engine, LoadsAndRunsEveryOpKind) {
  const auto b = test::make_small_model();
  auto e = Engine::load_memory(b.data(), b.size());
  ASSERT_TRUE(e) << e.error().message();
  EXPECT_EQ((*e)->op_count(), 12u);
  fill_input(**e);
  ASSERT_TRUE((*e)->run());
  const float* y = (*e)->output().f32();
  for (int i = 0; i < 7; ++i) EXPECT_TRUE(std::isfinite(y[i]));
}

TEST(Engine, RunIsDeterministicAndAllocatesNothing) {
  const auto b = test::make_small_model();
  auto loaded = Engine::load_memory(b.data(), b.size());
  ASSERT_TRUE(loaded);
  Engine& e = **loaded;
  fill_input(e);
  ASSERT_TRUE(e.run());
  float first[7];
  std::memcpy(first, e.output().f32(), sizeof first);
  const AllocationScope scope;
  for (int i = 0; i < 1000; ++i) {
    fill_input(e);
    ASSERT_TRUE(e.run());
  }
  EXPECT_EQ(scope.count(), 0u);
  EXPECT_EQ(std::memcmp(first, e.output().f32(), sizeof first), 0);
}

void* volatile g_sink;  // keeps the compiler from eliding the allocations below

TEST(Engine, CountsAllocationsWhenThereAreSome) {
  // The counter itself must see allocations, or the zero above proves nothing.
  const AllocationScope scope;
  g_sink = ::operator new(64);
  ::operator delete(g_sink);
  EXPECT_EQ(scope.count(), 1u);
  if (allocation_counter_covers_malloc()) {
    g_sink = std::malloc(32);
    std::free(g_sink);
    EXPECT_EQ(scope.count(), 2u);
  }
}

TEST(Engine, UsesCallerMemory) {
  const auto b = test::make_small_model();
  auto need = Engine::memory_required(b.data(), b.size());
  ASSERT_TRUE(need) << need.error().message();
  std::vector<uint8_t> storage(*need + 64);
  auto* aligned = reinterpret_cast<uint8_t*>((reinterpret_cast<uintptr_t>(storage.data()) + 63) &
                                             ~uintptr_t(63));
  EngineOptions opt;
  opt.memory = aligned;
  opt.memory_bytes = *need;
  opt.lock_memory = false;
  auto e = Engine::load_memory(b.data(), b.size(), opt);
  ASSERT_TRUE(e) << e.error().message();
  EXPECT_TRUE((*e)->memory().caller_memory);
  fill_input(**e);
  ASSERT_TRUE((*e)->run());
  const auto* in = static_cast<uint8_t*>((*e)->input().data);
  EXPECT_GE(in, aligned);
  EXPECT_LT(in, aligned + *need);

  opt.memory_bytes = *need - 1;
  auto small = Engine::load_memory(b.data(), b.size(), opt);
  ASSERT_FALSE(small);
  EXPECT_EQ(small.error().code(), Errc::kInvalidArgument);
  opt.memory = aligned + 4;
  opt.memory_bytes = *need;
  auto misaligned = Engine::load_memory(b.data(), b.size(), opt);
  ASSERT_FALSE(misaligned);
  EXPECT_NE(std::strstr(misaligned.error().message(), "aligned"), nullptr);
}

TEST(Engine, RefusesWrongModality) {
  const auto b = test::make_small_model();
  EngineOptions opt;
  opt.expect_modality = uint32_t(format::Modality::kLidarBev);
  auto e = Engine::load_memory(b.data(), b.size(), opt);
  ASSERT_FALSE(e);
  EXPECT_EQ(e.error().code(), Errc::kWrongTarget);
  EXPECT_NE(std::strstr(e.error().message(), "modality 'image'"), nullptr);
}

TEST(Engine, ReportsMemoryPlan) {
  const auto b = test::make_small_model();
  auto e = Engine::load_memory(b.data(), b.size());
  ASSERT_TRUE(e);
  const MemoryReport& m = (*e)->memory();
  EXPECT_GT(m.arena_bytes, 0u);
  EXPECT_LE(m.arena_bytes, m.arena_sum_bytes);
  EXPECT_GE(m.arena_bytes, m.arena_lower_bound_bytes);
  EXPECT_EQ(m.total_bytes,
            m.tables_bytes + m.kept_bytes + m.packed_bytes + m.arena_bytes + m.scratch_bytes);
}

// The bytes loaded through Engine::load_file from a temporary file.
Expected<std::unique_ptr<Engine>> load_via_file(const std::vector<uint8_t>& bytes) {
  char path[] = "/tmp/aprt_engine_test_XXXXXX";
  const int fd = mkstemp(path);
  if (fd < 0) return Error(Errc::kIo, "mkstemp failed");
  const bool written = write(fd, bytes.data(), bytes.size()) == long(bytes.size());
  close(fd);
  auto e = written ? Engine::load_file(path)
                   : Expected<std::unique_ptr<Engine>>(Error(Errc::kIo, "write failed"));
  unlink(path);
  return e;
}

// One copy of the weights: the caller's bytes are not referenced after load
// (overwriting them changes nothing), each constant is either kept or packed,
// and names survive the move of the tables.
TEST(Engine, KeepsOneCopyOfTheWeightsAndNothingOfTheCallersBytes) {
  for (const char* isa : {"ref", "auto"}) {
    SCOPED_TRACE(isa);
    auto b = test::make_small_model();
    EngineOptions opt;
    opt.isa = isa;
    auto loaded = Engine::load_memory(b.data(), b.size(), opt);
    ASSERT_TRUE(loaded) << loaded.error().message();
    Engine& e = **loaded;
    fill_input(e);
    ASSERT_TRUE(e.run());
    float before[7];
    std::memcpy(before, e.output().f32(), sizeof before);
    const std::string first_op = e.op(0).name;
    std::memset(b.data(), 0xA5, b.size());
    fill_input(e);
    ASSERT_TRUE(e.run());
    EXPECT_EQ(std::memcmp(before, e.output().f32(), sizeof before), 0);
    EXPECT_EQ(first_op, e.op(0).name);
    const MemoryReport& m = e.memory();
    size_t kept = 0, released = 0;
    for (size_t i = 0; i < e.tensor_count(); ++i) {
      const Tensor& t = e.tensor(i);
      if (!t.is_const()) continue;
      if (t.data) {
        ++kept;
        const auto* p = static_cast<const uint8_t*>(t.data);
        EXPECT_TRUE(p < b.data() || p >= b.data() + b.size()) << t.name;
      } else {
        ++released;
      }
    }
    EXPECT_EQ(kept, m.kept_count);
    EXPECT_LT(m.tables_bytes, m.file_bytes - m.weight_bytes + 64);
    if (std::strcmp(e.isa(), "ref") == 0) {
      EXPECT_EQ(released, 0u);  // the reference kernels read every weight as stored
    } else {
      EXPECT_GT(released, 0u);
      EXPECT_LT(m.kept_bytes, m.weight_bytes);
    }
  }
}

TEST(Engine, LoadFileMatchesLoadMemory) {
  const auto b = test::make_small_model();
  auto from_file = load_via_file(b);
  ASSERT_TRUE(from_file) << from_file.error().message();
  auto from_memory = Engine::load_memory(b.data(), b.size());
  ASSERT_TRUE(from_memory);
  fill_input(**from_file);
  fill_input(**from_memory);
  ASSERT_TRUE((*from_file)->run());
  ASSERT_TRUE((*from_memory)->run());
  EXPECT_EQ(std::memcmp((*from_file)->output().f32(), (*from_memory)->output().f32(), 7 * 4), 0);
  EXPECT_EQ((*from_file)->memory().total_bytes, (*from_memory)->memory().total_bytes);
}

TEST(Engine, LoadFileRefusesACorruptFile) {
  auto b = test::make_small_model();
  b[b.size() - 3] ^= 0x40;  // in the weights, the last section
  auto e = load_via_file(b);
  ASSERT_FALSE(e);
  EXPECT_EQ(e.error().code(), Errc::kChecksum);
  EXPECT_NE(std::strstr(e.error().message(), "WEIGHTS checksum mismatch"), nullptr)
      << e.error().message();
}

TEST(Engine, LoadFileRefusesATruncatedFile) {
  auto b = test::make_small_model();
  b.resize(b.size() / 2);
  auto e = load_via_file(b);
  ASSERT_FALSE(e);
  EXPECT_EQ(e.error().code(), Errc::kTruncated);
  EXPECT_NE(std::strstr(e.error().message(), "truncated"), nullptr) << e.error().message();
}

TEST(Engine, LoadFileReportsMissingFile) {
  auto e = Engine::load_file("/nonexistent/model.aprt");
  ASSERT_FALSE(e);
  EXPECT_EQ(e.error().code(), Errc::kIo);
  EXPECT_NE(std::strstr(e.error().message(), "cannot open"), nullptr);
}

}  // namespace
}  // namespace aprt

namespace aprt {
namespace {

// Runs the small model with `isa` and `threads`; returns the output.
std::vector<float> run_small(const char* isa, int threads) {
  const auto b = test::make_small_model();
  EngineOptions opt;
  opt.isa = isa;
  opt.threads = threads;
  opt.lock_memory = false;
  auto e = Engine::load_memory(b.data(), b.size(), opt);
  if (!e) return {};
  fill_input(**e);
  for (int i = 0; i < 3; ++i) (void)(*e)->run();
  return std::vector<float>((*e)->output().f32(), (*e)->output().f32() + 7);
}

TEST(Engine, ThreadCountDoesNotChangeOneBit) {
  const auto one = run_small("auto", 1);
  ASSERT_EQ(one.size(), 7u);
  for (int threads : {2, 3, 4}) {
    const auto many = run_small("auto", threads);
    ASSERT_EQ(many.size(), 7u);
    EXPECT_EQ(std::memcmp(one.data(), many.data(), 7 * sizeof(float)), 0) << threads << " threads";
  }
}

TEST(Engine, EveryIsaAgreesWithTheReference) {
  const auto ref = run_small("ref", 1);
  ASSERT_EQ(ref.size(), 7u);
  for (const char* isa : {"avx2", "avx512", "neon"}) {
    EngineOptions opt;
    opt.isa = isa;
    const auto b = test::make_small_model();
    auto e = Engine::load_memory(b.data(), b.size(), opt);
    if (!e) {
      EXPECT_EQ(e.error().code(), Errc::kIsaUnavailable) << e.error().message();
      continue;  // not compiled in, or not runnable on this CPU: refused, never SIGILL
    }
    const auto got = run_small(isa, 2);
    for (int i = 0; i < 7; ++i) EXPECT_NEAR(got[i], ref[i], 1e-4 * (1 + std::fabs(ref[i]))) << isa;
  }
}

TEST(Engine, RefusesUnknownIsaAndBadThreadCounts) {
  const auto b = test::make_small_model();
  EngineOptions opt;
  opt.isa = "sse9";
  auto e = Engine::load_memory(b.data(), b.size(), opt);
  ASSERT_FALSE(e);
  EXPECT_NE(std::strstr(e.error().message(), "unknown ISA"), nullptr);
  opt.isa = nullptr;
  opt.threads = 0;
  auto t = Engine::load_memory(b.data(), b.size(), opt);
  ASSERT_FALSE(t);
  EXPECT_EQ(t.error().code(), Errc::kInvalidArgument);
}

TEST(Engine, MultiThreadedRunAllocatesNothing) {
  const auto b = test::make_small_model();
  EngineOptions opt;
  opt.threads = 2;
  auto e = Engine::load_memory(b.data(), b.size(), opt);
  ASSERT_TRUE(e) << e.error().message();
  fill_input(**e);
  (void)(*e)->run();
  const AllocationScope scope;
  for (int i = 0; i < 200; ++i) ASSERT_TRUE((*e)->run());
  EXPECT_EQ(scope.count(), 0u);
}

}  // namespace
}  // namespace aprt
