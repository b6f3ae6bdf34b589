// The one kernel picker: what "auto" picks runs on this CPU and carries the
// int8 and bf16 parts that go with it; "ref" is the reference; a forced ISA
// this build or CPU lacks, or an unknown name, is refused with its reason.
#include "kernels/table/kernel_table.h"

#include <gtest/gtest.h>

#include <cstring>
#include <string>

#include "kernels/table/cpu_features.h"

namespace aprt::kernels {
namespace {

TEST(KernelTable, AutoPicksTheBestPartsThisCpuRuns) {
  auto t = pick_kernels("auto");
  ASSERT_TRUE(t) << t.error().message();
  const CpuFeatures& f = cpu_features();
  const bool any = !isa_parts().empty() && (f.avx2_fma || f.avx512 || f.neon);
  if (!any) {
    EXPECT_EQ(t->f32, nullptr);
    EXPECT_STREQ(t->name(), "ref");
    return;
  }
  ASSERT_NE(t->f32, nullptr);
  ASSERT_NE(t->qs8, nullptr);
  if (f.avx512) {
    EXPECT_STREQ(t->f32->isa, "avx512");
    EXPECT_STREQ(t->qs8->isa, f.avx512_vnni ? "avx512vnni" : "avx2");
    EXPECT_EQ(t->bf16 != nullptr, f.avx512_bf16);
  } else if (f.avx2_fma) {
    EXPECT_STREQ(t->f32->isa, "avx2");
    EXPECT_STREQ(t->qs8->isa, "avx2");
    EXPECT_EQ(t->bf16, nullptr);
  } else if (f.neon) {
    EXPECT_STREQ(t->f32->isa, "neon");
    EXPECT_STREQ(t->qs8->isa, f.neon_dot ? "neondot" : "neon");
  }
  EXPECT_STREQ(t->name(), t->f32->isa);
  auto same = pick_kernels(nullptr);
  ASSERT_TRUE(same);
  EXPECT_EQ(same->f32, t->f32);
  EXPECT_EQ(same->qs8, t->qs8);
}

TEST(KernelTable, RefIsTheReference) {
  auto t = pick_kernels("ref");
  ASSERT_TRUE(t);
  EXPECT_EQ(t->f32, nullptr);
  EXPECT_EQ(t->qs8, nullptr);
  EXPECT_EQ(t->bf16, nullptr);
  EXPECT_STREQ(t->name(), "ref");
}

TEST(KernelTable, ForcedIsaRunsOrIsRefusedWithItsReason) {
  for (const char* isa : {"avx512", "avx2", "neon"}) {
    auto t = pick_kernels(isa);
    bool listed = false, runs = false;
    for (const IsaParts& p : isa_parts()) {
      if (std::strcmp(p.isa, isa) == 0) listed = true, runs = p.f32_runs;
    }
    if (listed && runs) {
      ASSERT_TRUE(t) << t.error().message();
      EXPECT_STREQ(t->f32->isa, isa);
    } else {
      ASSERT_FALSE(t) << isa;
      EXPECT_NE(std::string(t.error().message()).find(isa), std::string::npos);
      EXPECT_NE(std::string(t.error().message())
                    .find(listed ? "cannot run" : "not compiled into this build"),
                std::string::npos)
          << t.error().message();
    }
  }
  auto bad = pick_kernels("sse9");
  ASSERT_FALSE(bad);
  EXPECT_NE(std::string(bad.error().message()).find("unknown ISA 'sse9'"), std::string::npos);
}

TEST(KernelTable, EveryPartIsNamedAndComplete) {
  for (const IsaParts& p : isa_parts()) {
    ASSERT_NE(p.f32, nullptr);
    EXPECT_STREQ(p.f32->isa, p.isa);
    EXPECT_NE(p.f32->gemm, nullptr);
    EXPECT_NE(p.f32->softmax_rows, nullptr);
    EXPECT_NE(p.f32->preprocess, nullptr);
    EXPECT_EQ(p.f32->gemm_nr % p.f32->lanes, 0);
    for (const QKernelSet* q : p.qs8) {
      if (!q) continue;
      EXPECT_NE(q->gemm, nullptr) << q->isa;
      EXPECT_NE(q->dwconv_rows, nullptr) << q->isa;
      EXPECT_EQ(q->attn_block != nullptr, q->attn_kq_bytes != nullptr) << q->isa;
    }
  }
}

}  // namespace
}  // namespace aprt::kernels
