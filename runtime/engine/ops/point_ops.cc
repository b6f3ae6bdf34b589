// The PointNet++ ops of the raw-points modality (model_bin/FORMAT.md, "Point
// ops"; tools/aprt_tools/model/point_ops.py is their definition):
//   FPS          X [N, W]                          -> Y [S, 3]
//   BALL_GROUP   P [N, Wp], C [S, Wc], F [N, Cf]?  -> Y [1, S, K, 3 + Cf]   params: radius
//   GROUP_MAX    X [1, S, K, C]                    -> Y [1, S, 1, C]
//   THREE_INTERP T [Nt, Wt], P [Np, Wp], F [Np, C] -> Y [Nt, C]
//   GRID_TOKENS  P [N, Wp], F [N, C]               -> Y [1, G, gx gy, C]  params: G, gx, gy
// Coordinates are the first three columns of a row tensor (the input's
// features, or an op's [S, 3] output). Every index these ops pick depends on
// coordinates only and is the same on every path (reference or fast, any
// thread count); FPS and the tokenisation run on one thread, grouping and
// interpolation split their centres / targets over the pool.
#include "kernels/points/pointnet__ref.h"
#include "kernels/points/pointnet_fast.h"
#include "runtime/engine/ops/op_common.h"
#include "runtime/engine/ops/ops.h"

namespace aprt::ops {
namespace {

struct PointState {
  int n = 0, stride = 0;    // points of the first operand and its row width
  int m = 0, m_stride = 0;  // centres / targets, known points (second operand)
  int k = 0, c = 0;         // neighbours, feature channels
  int groups = 0, gx = 0, gy = 0;
  float radius = 0.0f;
  Split split;
};

// A row tensor whose first three columns are coordinates: rows and width.
Status expect_coords(const OpNode& node, const Tensor* t, const char* role, int* rows, int* width) {
  Status st;
  if (!(st = expect_f32(node, t, role, false))) return st;
  APRT_OP_ENSURE(node, t->last_dim() >= 3, Errc::kShapeMismatch,
                 "%s '%s' has rows of %d values; coordinates need 3", role, t->name, t->last_dim());
  *rows = int(t->rows());
  *width = t->last_dim();
  return ok();
}

Split point_split(const OpNode& node, int count, int64_t work_per_item) {
  int tasks = node.threads <= 1 ? 1 : 2 * node.threads;
  const int64_t min_items = work_per_item > 0 ? (1 << 16) / work_per_item + 1 : count;
  if (tasks > count / min_items) tasks = int(count / min_items);
  return make_split(count, 1, tasks < 1 ? 1 : tasks);
}

// ---- FPS -----------------------------------------------------------------

void gather_xyz(const float* x, size_t stride, const uint32_t* idx, int s, float* y) {
  for (int i = 0; i < s; ++i) {
    const float* p = x + size_t(idx[i]) * stride;
    y[3 * i] = p[0];
    y[3 * i + 1] = p[1];
    y[3 * i + 2] = p[2];
  }
}

void eval_fps_ref(const OpNode& node, const RunContext& ctx) {
  const auto& s = node.state_as<PointState>();
  uint32_t* idx = reinterpret_cast<uint32_t*>(ctx.scratch + s.n);
  kernels::f32_fps__ref(node.in[0]->f32(), size_t(s.stride), size_t(s.n), size_t(s.m), idx,
                        ctx.scratch);
  gather_xyz(node.in[0]->f32(), size_t(s.stride), idx, s.m, node.out[0]->f32());
}

void eval_fps_fast(const OpNode& node, const RunContext& ctx) {
  const auto& s = node.state_as<PointState>();
  float* soa = ctx.scratch;
  float* dist = soa + 3 * size_t(s.n);
  uint32_t* idx = reinterpret_cast<uint32_t*>(dist + s.n);
  kernels::f32_points_to_soa(node.in[0]->f32(), size_t(s.stride), size_t(s.n), soa);
  kernels::f32_fps_soa(soa, size_t(s.n), size_t(s.m), idx, dist);
  gather_xyz(node.in[0]->f32(), size_t(s.stride), idx, s.m, node.out[0]->f32());
}

// ---- BALL_GROUP -------------------------------------------------------------

const float* feats_of(const OpNode& node, int i) {
  return node.n_in > i && node.in[i] ? node.in[i]->f32() : nullptr;
}

void eval_ball_ref(const OpNode& node, const RunContext&) {
  const auto& s = node.state_as<PointState>();
  kernels::f32_ball_group__ref(node.in[0]->f32(), size_t(s.stride), size_t(s.n), node.in[1]->f32(),
                               size_t(s.m_stride), 0, s.m, s.radius, s.k, feats_of(node, 2), s.c,
                               node.out[0]->f32());
}

struct SoaTask {
  const OpNode* node;
  const float* soa;
};

void ball_fast_task(void* data, int task, int) {
  const auto* t = static_cast<const SoaTask*>(data);
  const OpNode& node = *t->node;
  const auto& s = node.state_as<PointState>();
  kernels::f32_ball_group_soa(t->soa, size_t(s.n), node.in[1]->f32(), size_t(s.m_stride),
                              s.split.begin(task), s.split.end(task), s.radius, s.k,
                              feats_of(node, 2), s.c, node.out[0]->f32());
}

void eval_ball_fast(const OpNode& node, const RunContext& ctx) {
  const auto& s = node.state_as<PointState>();
  kernels::f32_points_to_soa(node.in[0]->f32(), size_t(s.stride), size_t(s.n), ctx.scratch);
  SoaTask t{&node, ctx.scratch};
  parallel_for(ctx, s.split.tasks, ball_fast_task, &t);
}

// ---- GROUP_MAX ----------------------------------------------------------------

void eval_group_max_ref(const OpNode& node, const RunContext&) {
  const auto& s = node.state_as<PointState>();
  kernels::f32_group_max__ref(s.k, s.c, node.in[0]->f32(), node.out[0]->f32(), 0, s.m);
}

void group_max_task(void* data, int task, int) {
  const auto& node = *static_cast<const OpNode*>(data);
  const auto& s = node.state_as<PointState>();
  kernels::f32_group_max(s.k, s.c, node.in[0]->f32(), node.out[0]->f32(), s.split.begin(task),
                         s.split.end(task));
}

void eval_group_max_fast(const OpNode& node, const RunContext& ctx) {
  parallel_for(ctx, node.state_as<PointState>().split.tasks, group_max_task,
               const_cast<OpNode*>(&node));
}

// ---- THREE_INTERP ---------------------------------------------------------------

void eval_interp_ref(const OpNode& node, const RunContext&) {
  const auto& s = node.state_as<PointState>();
  kernels::f32_three_interp__ref(node.in[0]->f32(), size_t(s.stride), 0, s.n, node.in[1]->f32(),
                                 size_t(s.m_stride), size_t(s.m), node.in[2]->f32(), s.c,
                                 node.out[0]->f32());
}

struct InterpTask {
  const OpNode* node;
  const float* soa;
  const RunContext* ctx;
};

void interp_fast_task(void* data, int task, int thread) {
  const auto* t = static_cast<const InterpTask*>(data);
  const OpNode& node = *t->node;
  const auto& s = node.state_as<PointState>();
  kernels::f32_three_interp_soa(node.in[0]->f32(), size_t(s.stride), s.split.begin(task),
                                s.split.end(task), t->soa, size_t(s.m), node.in[2]->f32(), s.c,
                                node.out[0]->f32(), t->ctx->thread_scratch[thread]);
}

void eval_interp_fast(const OpNode& node, const RunContext& ctx) {
  const auto& s = node.state_as<PointState>();
  kernels::f32_points_to_soa(node.in[1]->f32(), size_t(s.m_stride), size_t(s.m), ctx.scratch);
  InterpTask t{&node, ctx.scratch, &ctx};
  parallel_for(ctx, s.split.tasks, interp_fast_task, &t);
}

// ---- GRID_TOKENS ------------------------------------------------------------------

void eval_grid_tokens(const OpNode& node, const RunContext& ctx) {
  const auto& s = node.state_as<PointState>();
  kernels::f32_grid_tokens__ref(node.in[0]->f32(), size_t(s.stride), size_t(s.n), s.groups, s.gx,
                                s.gy, node.in[1]->f32(), s.c, node.out[0]->f32(), ctx.scratch);
}

}  // namespace

Status prepare_fps(OpNode& node) {
  auto& s = node.state_as<PointState>();
  Status st;
  if (!(st = expect_coords(node, node.in[0], "points", &s.n, &s.stride))) return st;
  const Tensor* y = node.out[0];
  if (!(st = expect_f32(node, y, "output", false))) return st;
  APRT_OP_ENSURE(node, y->last_dim() == 3, Errc::kShapeMismatch,
                 "output '%s' must have rows of 3 coordinates, has %d", y->name, y->last_dim());
  s.m = int(y->rows());
  APRT_OP_ENSURE(node, s.m >= 1 && s.m <= s.n, Errc::kShapeMismatch,
                 "samples %d of %d points (1..%d allowed)", s.m, s.n, s.n);
  node.flops = 8ull * uint64_t(s.n) * uint64_t(s.m);
  if (node.ks) {
    node.scratch_floats = 4 * size_t(s.n) + size_t(s.m);
    node.eval = eval_fps_fast;
    node.kernel = "portable";
  } else {
    node.scratch_floats = size_t(s.n) + size_t(s.m);
    node.eval = eval_fps_ref;
  }
  return ok();
}

Status prepare_ball_group(OpNode& node) {
  auto& s = node.state_as<PointState>();
  Status st;
  if (!(st = expect_coords(node, node.in[0], "points", &s.n, &s.stride))) return st;
  if (!(st = expect_coords(node, node.in[1], "centres", &s.m, &s.m_stride))) return st;
  const Tensor* f = node.n_in > 2 ? node.in[2] : nullptr;
  if (f) {
    if (!(st = expect_f32(node, f, "features", false))) return st;
    APRT_OP_ENSURE(node, int(f->rows()) == s.n, Errc::kShapeMismatch,
                   "features '%s' have %zu rows for %d points", f->name, f->rows(), s.n);
    s.c = f->last_dim();
  }
  const Tensor* y = node.out[0];
  if (!(st = expect_f32(node, y, "output", false))) return st;
  APRT_OP_ENSURE(node,
                 y->rank == 4 && y->dims[0] == 1 && y->dims[1] == s.m && y->dims[3] == 3 + s.c,
                 Errc::kShapeMismatch, "output '%s' must be [1, %d, K, %d]", y->name, s.m, 3 + s.c);
  s.k = y->dims[2];
  s.radius = param_f32(node, 0);
  APRT_OP_ENSURE(node, std::isfinite(s.radius) && s.radius > 0.0f, Errc::kBadOp,
                 "radius %g must be finite and > 0", double(s.radius));
  node.flops = 8ull * uint64_t(s.n) * uint64_t(s.m);
  if (node.ks) {
    s.split = point_split(node, s.m, int64_t(s.n) * 4);
    node.scratch_floats = 3 * size_t(s.n);
    node.eval = eval_ball_fast;
    node.kernel = "portable";
  } else {
    node.eval = eval_ball_ref;
  }
  return ok();
}

Status prepare_group_max(OpNode& node) {
  auto& s = node.state_as<PointState>();
  const Tensor* x = node.in[0];
  const Tensor* y = node.out[0];
  Status st;
  if (!(st = expect_f32(node, x, "input", false))) return st;
  if (!(st = expect_f32(node, y, "output", false))) return st;
  APRT_OP_ENSURE(node, x->rank == 4 && x->dims[0] == 1, Errc::kShapeMismatch,
                 "input '%s' must be [1, S, K, C]", x->name);
  s.m = x->dims[1];
  s.k = x->dims[2];
  s.c = x->dims[3];
  const int want[4] = {1, s.m, 1, s.c};
  if (!(st = expect_dims(node, y, "output", 4, want))) return st;
  node.flops = x->numel;
  if (node.ks) {
    s.split = point_split(node, s.m, int64_t(s.k) * s.c);
    node.eval = eval_group_max_fast;
    node.kernel = "portable";
  } else {
    node.eval = eval_group_max_ref;
  }
  return ok();
}

Status prepare_three_interp(OpNode& node) {
  auto& s = node.state_as<PointState>();
  Status st;
  if (!(st = expect_coords(node, node.in[0], "targets", &s.n, &s.stride))) return st;
  if (!(st = expect_coords(node, node.in[1], "known points", &s.m, &s.m_stride))) return st;
  APRT_OP_ENSURE(node, s.m >= 3, Errc::kShapeMismatch,
                 "interpolation needs at least 3 known points, has %d", s.m);
  const Tensor* f = node.in[2];
  if (!(st = expect_f32(node, f, "features", false))) return st;
  APRT_OP_ENSURE(node, int(f->rows()) == s.m, Errc::kShapeMismatch,
                 "features '%s' have %zu rows for %d known points", f->name, f->rows(), s.m);
  s.c = f->last_dim();
  const Tensor* y = node.out[0];
  if (!(st = expect_f32(node, y, "output", false))) return st;
  APRT_OP_ENSURE(node, int(y->rows()) == s.n && y->last_dim() == s.c, Errc::kShapeMismatch,
                 "output '%s' must be %d x %d", y->name, s.n, s.c);
  node.flops = 8ull * uint64_t(s.n) * uint64_t(s.m) + 6ull * uint64_t(s.n) * uint64_t(s.c);
  if (node.ks) {
    s.split = point_split(node, s.n, int64_t(s.m) * 4 + s.c);
    node.scratch_floats = 3 * size_t(s.m);
    node.thread_scratch_floats = size_t(s.m);
    node.eval = eval_interp_fast;
    node.kernel = "portable";
  } else {
    node.eval = eval_interp_ref;
  }
  return ok();
}

Status prepare_grid_tokens(OpNode& node) {
  auto& s = node.state_as<PointState>();
  Status st;
  if (!(st = expect_coords(node, node.in[0], "points", &s.n, &s.stride))) return st;
  const Tensor* f = node.in[1];
  if (!(st = expect_f32(node, f, "features", false))) return st;
  APRT_OP_ENSURE(node, int(f->rows()) == s.n, Errc::kShapeMismatch,
                 "features '%s' have %zu rows for %d points", f->name, f->rows(), s.n);
  s.c = f->last_dim();
  s.groups = node.params[0];
  s.gx = node.params[1];
  s.gy = node.params[2];
  APRT_OP_ENSURE(
      node,
      s.groups >= 1 && s.gx >= 1 && s.gy >= 1 && s.groups <= 4096 && s.gx <= 4096 && s.gy <= 4096,
      Errc::kBadOp, "token grid %d x %d x %d (each 1..4096)", s.groups, s.gx, s.gy);
  const int64_t cells = int64_t(s.groups) * s.gx * s.gy;
  APRT_OP_ENSURE(node, s.n % cells == 0, Errc::kShapeMismatch,
                 "%d points do not split into %d x %d x %d cells", s.n, s.groups, s.gx, s.gy);
  const int want[4] = {1, s.groups, s.gx * s.gy, s.c};
  if (!(st = expect_dims(node, node.out[0], "output", 4, want))) return st;
  node.scratch_floats = 4 * size_t(s.n);
  node.flops = uint64_t(s.n) * uint64_t(s.c);
  node.eval = eval_grid_tokens;
  return ok();
}

}  // namespace aprt::ops
