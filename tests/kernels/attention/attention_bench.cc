// The attention family: the fused fp32 kernel, int8 scores and bf16.
#include <benchmark/benchmark.h>

#include <cmath>
#include <cstring>
#include <random>
#include <vector>

#include "kernels/attention/qs8_attention.h"
#include "kernels/table/kernel_table.h"
#include "tests/kernels/bench_support.h"

namespace aprt::kernels::bench {

// Fused attention: Lq = Lk = L, heads x d, one thread.
void BM_Attention(benchmark::State& state) {
  const int l = int(state.range(0)), heads = int(state.range(1)), d = int(state.range(2));
  const int e = heads * d;
  const auto q = rnd(size_t(l) * e), k = rnd(size_t(l) * e), v = rnd(size_t(l) * e);
  const int lk_pad = (l + g_ks->attn_key_block - 1) / g_ks->attn_key_block * g_ks->attn_key_block;
  Buf kt(size_t(e) * lk_pad), vp(size_t(e) * lk_pad), o(size_t(l) * e),
      scratch(g_ks->attn_scratch(d));
  for (auto _ : state) {
    for (int h = 0; h < heads; ++h) {
      g_ks->attn_pack_kv(l, lk_pad, d, k.data(), size_t(e), v.data(), size_t(e), h, kt.data(),
                         vp.data());
    }
    for (int h = 0; h < heads; ++h) {
      for (int q0 = 0; q0 < l; q0 += g_ks->attn_max_rows) {
        const int rows = l - q0 < g_ks->attn_max_rows ? l - q0 : g_ks->attn_max_rows;
        g_ks->attn_block(rows, l, d, q.data(), size_t(e), kt.data(), vp.data(), lk_pad, 0.17f,
                         o.data(), size_t(e), h, q0, scratch.data());
      }
    }
    benchmark::DoNotOptimize(o.data());
  }
  add_peak_counter(state, 4.0 * l * l * e);
}

// The same attention with int8 scores (kernels/attention/qs8_attention.h): Q and
// K quantised per row and head, the int8 table's kernel; "GFLOP/s" counts the
// fp32 attention's flops, so it compares with BM_Attention directly.
void BM_QAttention(benchmark::State& state) {
  const QKernelSet* qs = g_qs;
  if (!qs || !qs->attn_block) {
    state.SkipWithError("no int8-score attention for this CPU");
    return;
  }
  const int l = int(state.range(0)), heads = int(state.range(1)), d = int(state.range(2));
  const int e = heads * d;
  const auto q = rnd(size_t(l) * e), k = rnd(size_t(l) * e), v = rnd(size_t(l) * e);
  const int lk_pad = (l + qs->attn_key_block - 1) / qs->attn_key_block * qs->attn_key_block;
  std::vector<uint8_t> kq(qs->attn_kq_bytes(heads, lk_pad, d));
  Buf vp(size_t(e) * lk_pad), o(size_t(l) * e), scratch(qs->attn_scratch(d));
  for (auto _ : state) {
    for (int h = 0; h < heads; ++h) {
      qs->attn_pack_kv(l, lk_pad, d, k.data(), size_t(e), v.data(), size_t(e), h, kq.data(),
                       vp.data());
    }
    for (int h = 0; h < heads; ++h) {
      for (int q0 = 0; q0 < l; q0 += qs->attn_max_rows) {
        const int rows = l - q0 < qs->attn_max_rows ? l - q0 : qs->attn_max_rows;
        qs->attn_block(rows, l, d, q.data(), size_t(e), kq.data(), vp.data(), lk_pad, 0.17f,
                       o.data(), size_t(e), h, q0, scratch.data());
      }
    }
    benchmark::DoNotOptimize(o.data());
  }
  add_peak_counter(state, 4.0 * l * l * e);
  state.SetLabel(qs->isa);
}

// The same attention in bf16 (kernels/attention/bf16_attention.h): Q, K, V and
// the weights rounded to bf16, vdpbf16ps for both products; "GFLOP/s" again
// counts the fp32 attention's flops against the fp32 FMA peak.
void BM_Bf16Attention(benchmark::State& state) {
  const Bf16AttentionKernels* bk = g_bf;
  if (!bk || !cpu_features().avx512_bf16 || std::string(g_ks->isa) != "avx512") {
    state.SkipWithError("no bf16 attention for this CPU / ISA");
    return;
  }
  const int l = int(state.range(0)), heads = int(state.range(1)), d = int(state.range(2));
  const int e = heads * d;
  const auto q = rnd(size_t(l) * e), k = rnd(size_t(l) * e), v = rnd(size_t(l) * e);
  const int lk_pad = (l + bk->key_block - 1) / bk->key_block * bk->key_block;
  std::vector<uint16_t> kv(bk->kv_bytes(heads, lk_pad, d) / 2);
  Buf o(size_t(l) * e), scratch(bk->scratch(d));
  for (auto _ : state) {
    for (int h = 0; h < heads; ++h)
      bk->pack_kv(l, lk_pad, d, k.data(), size_t(e), v.data(), size_t(e), h, kv.data());
    for (int h = 0; h < heads; ++h) {
      for (int q0 = 0; q0 < l; q0 += bk->max_rows) {
        const int rows = l - q0 < bk->max_rows ? l - q0 : bk->max_rows;
        bk->block(rows, l, d, q.data(), size_t(e), kv.data(), lk_pad, 0.17f, o.data(), size_t(e), h,
                  q0, scratch.data());
      }
    }
    benchmark::DoNotOptimize(o.data());
  }
  add_peak_counter(state, 4.0 * l * l * e);
  state.SetLabel(bk->isa);
}

BENCHMARK(BM_Attention)
    ->Args({784, 8, 32})
    ->Args({256, 8, 32})
    ->Args({196, 8, 32})
    ->Args({64, 8, 32});

BENCHMARK(BM_QAttention)->Args({784, 8, 32})->Args({196, 8, 32});
BENCHMARK(BM_Bf16Attention)->Args({784, 8, 32})->Args({196, 8, 32});

}  // namespace aprt::kernels::bench
