// The pose filter (runtime/pose/pose_filter.h, odometry_filter.h) and the
// odometry it runs on (drivers/input/odometry.h), on made-up drives: a fix
// starts from agreeing estimates and is then closer than they are, outliers
// are refused without moving it, a wrong start is taken over by a consistent
// run, a missing motion resets it, a long blind stretch makes it uncertain;
// the odometry integrates arcs exactly and refuses what it cannot cover.
#include "runtime/pose/pose_filter.h"

#include <gtest/gtest.h>

#include <cmath>
#include <random>
#include <vector>

#include "drivers/input/odometry.h"
#include "runtime/base/allocation_counter.h"
#include "runtime/pose/odometry_filter.h"
#include "runtime/pose/pose_flags.h"

namespace aprt {
namespace {

constexpr double kDt = 0.04;      // 25 Hz
constexpr double kSpeed = 10.0;   // m/s
constexpr double kYawRate = 0.2;  // rad/s: a 50 m radius circle

// base_link on the circle at time t: starts at (0, 0) heading east.
PlanarPose on_circle(double t) {
  const double r = kSpeed / kYawRate, a = kYawRate * t;
  PlanarPose p;
  p.x = r * std::sin(a);
  p.y = r * (1 - std::cos(a));
  p.yaw = a;
  return p;
}

PlanarMotion step_motion() {
  PlanarMotion m;
  const double a = kYawRate * kDt, r = kSpeed / kYawRate;
  m.dx = r * std::sin(a);
  m.dy = r * (1 - std::cos(a));
  m.dyaw = a;
  m.distance_m = kSpeed * kDt;
  m.dt_s = kDt;
  return m;
}

PlanarPose noisy(const PlanarPose& truth, std::mt19937& rng, double sigma_m, double sigma_rad) {
  std::normal_distribution<double> n(0.0, 1.0);
  PlanarPose z = truth;
  z.x += sigma_m * n(rng);
  z.y += sigma_m * n(rng);
  z.yaw += sigma_rad * n(rng);
  z.sigma_x = z.sigma_y = sigma_m;
  z.sigma_yaw = sigma_rad;
  return z;
}

double distance(const PlanarPose& a, const PlanarPose& b) {
  return std::hypot(a.x - b.x, a.y - b.y);
}

// Frames [from, to) of the circle with estimates of the given noise.
void drive(PoseFilter* f, std::mt19937* rng, int from, int to, double sigma_m, double sigma_rad) {
  const PlanarMotion m = step_motion();
  for (int k = from; k < to; ++k) {
    const PlanarPose z = noisy(on_circle(k * kDt), *rng, sigma_m, sigma_rad);
    (void)f->step(&m, &z);
  }
}

PoseFilterParams params() {
  PoseFilterParams p;
  p.enabled = true;
  p.confirm = 4;
  p.take_over_after = 25;
  p.max_radius_m = 8.0;
  p.max_yaw_deg = 5.0;
  return p;
}

TEST(PoseFilter, StartsFromAgreeingEstimatesThenBeatsThem) {
  PoseFilter f(params());
  std::mt19937 rng(7);
  const PlanarMotion m = step_motion();
  double sum_filter = 0, sum_estimate = 0;
  int n = 0;
  for (int k = 0; k < 500; ++k) {
    const PlanarPose truth = on_circle(k * kDt);
    const PlanarPose z = noisy(truth, rng, 3.0, 0.03);
    const PoseFilter::Output o = f.step(&m, &z);
    if (k < 3) {
      EXPECT_FALSE(o.fix) << k;
      EXPECT_EQ(o.flags & kPoseUnconfirmed, kPoseUnconfirmed);
    }
    if (k == 3) {
      EXPECT_EQ(o.use, PoseFilter::Use::kStarted);
    }
    if (k >= 100) {
      EXPECT_EQ(o.flags, 0u) << k;
      EXPECT_GT(o.radius95_m, 0.0) << k;  // valid: its own region within the limit
      EXPECT_LE(o.radius95_m, params().max_radius_m) << k;
      sum_filter += distance(o.pose, truth);
      sum_estimate += distance(z, truth);
      ++n;
    }
  }
  // Many frames averaged along an exact odometry: several times closer.
  EXPECT_LT(sum_filter / n, 0.3 * sum_estimate / n);
}

// The model's sigma overstated 3x (calibrated over a heavy tail the filter
// refuses): weighed at a third, the same estimates make a valid fix sooner
// and a tighter covariance; an unconfirmed output still carries the model's
// own sigma.
TEST(PoseFilter, EstimateSigmaScaleWeighsTheModelsSigma) {
  PoseFilterParams plain = params();
  plain.max_radius_m = 6.0;
  PoseFilterParams scaled = plain;
  scaled.estimate_sigma_scale = 1.0 / 3.0;
  PoseFilter a(plain), b(scaled);
  std::mt19937 rng_a(11), rng_b(11);
  const PlanarMotion m = step_motion();
  int first_valid_a = -1, first_valid_b = -1;
  for (int k = 0; k < 300; ++k) {
    const PlanarPose truth = on_circle(k * kDt);
    PlanarPose za = noisy(truth, rng_a, 2.0, 0.02), zb = noisy(truth, rng_b, 2.0, 0.02);
    za.sigma_x = za.sigma_y = zb.sigma_x = zb.sigma_y = 6.0;  // stated: 3x the true 2 m
    const PoseFilter::Output oa = a.step(&m, &za), ob = b.step(&m, &zb);
    if (k == 0) {
      EXPECT_EQ(ob.pose.sigma_x, 6.0);  // no fix yet: the model's own
    }
    if (oa.flags == 0 && first_valid_a < 0) first_valid_a = k;
    if (ob.flags == 0 && first_valid_b < 0) first_valid_b = k;
    if (k == 299) {
      // Smaller (not a third: the odometry's noise is the same for both).
      EXPECT_LT(ob.pose.sigma_x, 0.8 * oa.pose.sigma_x);
    }
  }
  ASSERT_GE(first_valid_b, 0);
  EXPECT_TRUE(first_valid_a < 0 || first_valid_b < first_valid_a)
      << first_valid_a << " " << first_valid_b;
}

// A stretch of estimates all a few metres off the same way (the model's
// errors correlated over many frames, as in places on the town's drives):
// the filter follows them and, assuming independent estimates, believes the
// result. With disagreement_frames its published covariance takes in the
// estimates' mean disagreement, so the truth stays inside the 95 % ellipse
// far more often; with unbiased estimates it stays near the filter's own.
TEST(PoseFilter, DisagreementWidensTheCovarianceOverABiasedStretch) {
  PoseFilterParams plain = params();
  PoseFilterParams wide = plain;
  wide.disagreement_frames = 25;
  PoseFilter a(plain), b(wide);
  std::mt19937 rng(23);
  const PlanarMotion m = step_motion();
  int inside_a = 0, inside_b = 0;
  double sigma_a = 0, sigma_b = 0;
  for (int k = 0; k < 600; ++k) {
    const PlanarPose truth = on_circle(k * kDt);
    PlanarPose z = noisy(truth, rng, 2.0, 0.02);
    // Frames 200-299: 3 m off along x (within the stated 2 m sigma's gate).
    if (k >= 200 && k < 300) z.x += 3.0;
    const PoseFilter::Output oa = a.step(&m, &z), ob = b.step(&m, &z);
    ASSERT_EQ(oa.pose.x, ob.pose.x) << k;  // the same estimate (only the covariance differs)
    if (k >= 200 && k < 350) {
      const auto inside = [&](const PoseFilter::Output& o) {
        const double ex = o.pose.x - truth.x, ey = o.pose.y - truth.y;
        return ex * ex / (o.pose.sigma_x * o.pose.sigma_x) +
                   ey * ey / (o.pose.sigma_y * o.pose.sigma_y) <=
               5.991;
      };
      inside_a += inside(oa);
      inside_b += inside(ob);
    }
    if (k == 199) {
      // Unbiased so far: wider by about the noise of a mean of ~25 estimates
      // of 2 m (0.3 m), not more.
      EXPECT_LT(ob.pose.sigma_x, oa.pose.sigma_x + 0.6);
      EXPECT_GE(ob.pose.sigma_x, oa.pose.sigma_x);
    }
    if (k == 599) {
      sigma_a = oa.pose.sigma_x;
      sigma_b = ob.pose.sigma_x;
    }
  }
  EXPECT_LT(inside_a, 150 * 0.6) << inside_a;  // the plain filter believes the offset
  EXPECT_GT(inside_b, 150 * 0.85) << inside_b;
  EXPECT_LT(sigma_b, sigma_a + 0.6);  // and narrows again once the estimates agree
}

// Estimates whose error is half a bias that stays with the place (a
// Gauss-Markov process over the distance driven: 1.5 m, 5 m) and half white
// noise, each stating only its own 1 m sigma, as the town's drives measure
// (docs/evaluation.md). A filter that averages them as independent believes
// a mean that is not there; with the place bias in its state its 95 %
// ellipse holds the truth about 92 % of the time (the plain one: 12 %), and
// its pose is closer (it no longer follows each place's offset as news).
TEST(PoseFilter, APlaceBiasInTheStateMakesTheCovarianceHonest) {
  PoseFilterParams plain = params();
  PoseFilterParams placed = plain;
  placed.place_sigma_m = 1.5;
  placed.place_length_m = 5.0;
  PoseFilter a(plain), b(placed);
  std::mt19937 rng(41);
  std::normal_distribution<double> n(0.0, 1.0);
  const PlanarMotion m = step_motion();
  const double phi = std::exp(-m.distance_m / placed.place_length_m);
  double bias[2] = {1.5 * n(rng), 1.5 * n(rng)};
  int inside_a = 0, inside_b = 0, frames = 0;
  double sq_a = 0, sq_b = 0;
  const auto inside = [](const PoseFilter::Output& o, const PlanarPose& t) {
    const double ex = o.pose.x - t.x, ey = o.pose.y - t.y;
    const double sxx = o.pose.sigma_x * o.pose.sigma_x, syy = o.pose.sigma_y * o.pose.sigma_y;
    const double det = sxx * syy - o.cov_xy * o.cov_xy;
    return (syy * ex * ex - 2 * o.cov_xy * ex * ey + sxx * ey * ey) / det <= 5.991;
  };
  for (int k = 0; k < 3000; ++k) {
    for (double& c : bias) c = phi * c + 1.5 * std::sqrt(1 - phi * phi) * n(rng);
    const PlanarPose truth = on_circle(k * kDt);
    PlanarPose z = noisy(truth, rng, 1.0, 0.02);
    z.x += bias[0];
    z.y += bias[1];
    const PoseFilter::Output oa = a.step(&m, &z), ob = b.step(&m, &z);
    if (k < 100 || !oa.fix || !ob.fix) continue;
    ++frames;
    inside_a += inside(oa, truth);
    inside_b += inside(ob, truth);
    sq_a += std::pow(distance(oa.pose, truth), 2);
    sq_b += std::pow(distance(ob.pose, truth), 2);
  }
  ASSERT_GT(frames, 2800);
  EXPECT_LT(inside_a, 0.50 * frames) << inside_a << " of " << frames;
  EXPECT_GT(inside_b, 0.90 * frames) << inside_b << " of " << frames;
  EXPECT_LT(inside_b, 0.99 * frames) << inside_b << " of " << frames;
  EXPECT_LT(sq_b, 0.6 * sq_a) << std::sqrt(sq_b / frames) << " m against "
                              << std::sqrt(sq_a / frames) << " m RMS";
}

TEST(PoseFilter, OutliersAreRefusedAndDoNotMoveTheFix) {
  PoseFilter f(params());
  std::mt19937 rng(3);
  const PlanarMotion m = step_motion();
  drive(&f, &rng, 0, 100, 2.0, 0.02);
  for (int k = 100; k < 110; ++k) {
    const PlanarPose truth = on_circle(k * kDt);
    PlanarPose wrong = noisy(truth, rng, 2.0, 0.02);
    wrong.x += 60.0;  // the wrong street, confidently
    wrong.yaw += M_PI;
    const PoseFilter::Output o = f.step(&m, &wrong);
    EXPECT_EQ(o.use, PoseFilter::Use::kRefused) << k;
    EXPECT_EQ(o.flags, 0u) << k;  // the fix carries on with the odometry
    EXPECT_LT(distance(o.pose, truth), 2.0) << k;
  }
}

TEST(PoseFilter, AWrongStartIsTakenOverByAConsistentRun) {
  PoseFilterParams p = params();
  p.take_over_after = 10;
  PoseFilter f(p);
  std::mt19937 rng(5);
  const PlanarMotion m = step_motion();
  // Four agreeing but wrong estimates start a fix 80 m away...
  for (int k = 0; k < 4; ++k) {
    PlanarPose z = noisy(on_circle(k * kDt), rng, 0.0, 0.0);
    z.y += 80.0;
    z.sigma_x = z.sigma_y = 1.0;
    z.sigma_yaw = 0.01;
    (void)f.step(&m, &z);
  }
  ASSERT_TRUE(f.has_fix());
  // ...then the right ones: refused until 10 in a row, then they take over.
  bool took_over = false;
  for (int k = 4; k < 40; ++k) {
    const PlanarPose truth = on_circle(k * kDt);
    const PlanarPose z = noisy(truth, rng, 1.0, 0.01);
    const PoseFilter::Output o = f.step(&m, &z);
    if (o.use == PoseFilter::Use::kTookOver) {
      took_over = true;
      EXPECT_GE(k, 4 + 9);
    }
    if (k >= 20) {
      EXPECT_LT(distance(o.pose, truth), 3.0) << k;
    }
  }
  EXPECT_TRUE(took_over);
}

TEST(PoseFilter, WithoutMotionNothingCarriesOver) {
  PoseFilter f(params());
  std::mt19937 rng(1);
  drive(&f, &rng, 0, 50, 1.0, 0.01);
  ASSERT_TRUE(f.has_fix());
  const PlanarPose z = noisy(on_circle(50 * kDt), rng, 1.0, 0.01);
  const PoseFilter::Output o = f.step(nullptr, &z);
  EXPECT_EQ(o.flags, kPoseNoOdometry | kPoseUnconfirmed);
  EXPECT_FALSE(f.has_fix());
}

TEST(PoseFilter, ABlindStretchBecomesUncertainThenLost) {
  PoseFilterParams p = params();
  p.lost_radius_m = 30.0;
  PoseFilter f(p);
  std::mt19937 rng(2);
  const PlanarMotion m = step_motion();
  drive(&f, &rng, 0, 50, 1.0, 0.01);
  bool uncertain = false;
  for (int k = 50; k < 5000 && f.has_fix(); ++k) {
    const PoseFilter::Output o = f.step(&m, nullptr);  // no usable estimate
    uncertain = uncertain || (o.flags & kPoseUncertain);
  }
  EXPECT_TRUE(uncertain);
  EXPECT_FALSE(f.has_fix());
}

TEST(PoseFilter, StepAllocatesNothing) {
  PoseFilter f(params());
  std::mt19937 rng(4);
  const PlanarMotion m = step_motion();
  std::vector<PlanarPose> zs;
  for (int k = 0; k < 200; ++k) zs.push_back(noisy(on_circle(k * kDt), rng, 2.0, 0.02));
  OdometryFilterParams op;
  op.filter = params();
  OdometryFilter of(op, Eigen::Isometry3d::Identity());
  PoseEstimate e;
  e.has_sigma = true;
  e.sigma_position_m[0] = e.sigma_position_m[1] = e.sigma_position_m[2] = 2.0;
  e.sigma_rotation_rad[0] = e.sigma_rotation_rad[1] = e.sigma_rotation_rad[2] = 0.02;
  const AllocationScope scope;
  for (const PlanarPose& z : zs) {
    (void)f.step(&m, &z);
    e.position[0] = z.x;
    e.position[1] = z.y;
    e.orientation[0] = std::cos(z.yaw / 2);
    e.orientation[3] = std::sin(z.yaw / 2);
    (void)of.step(e, 0, &m);
  }
  EXPECT_EQ(scope.count(), 0u);
}

// The camera 1.2 m ahead of base_link, perfect estimates of it: the filter's
// published camera pose follows the truth through the turn (the lever arm
// turns with the vehicle).
TEST(OdometryFilter, TracksASensorAheadOfBaseLink) {
  OdometryFilterParams p;
  p.filter = params();
  Eigen::Isometry3d base_from_sensor = Eigen::Isometry3d::Identity();
  base_from_sensor.translation() = Eigen::Vector3d(1.2, 0, 1.5);
  OdometryFilter f(p, base_from_sensor);
  const PlanarMotion m = step_motion();
  for (int k = 0; k < 200; ++k) {
    const PlanarPose b = on_circle(k * kDt);
    PoseEstimate cam;
    cam.position[0] = b.x + 1.2 * std::cos(b.yaw);
    cam.position[1] = b.y + 1.2 * std::sin(b.yaw);
    cam.position[2] = 1.5;
    cam.orientation[0] = std::cos(b.yaw / 2);
    cam.orientation[3] = std::sin(b.yaw / 2);
    cam.has_sigma = true;
    cam.sigma_position_m[0] = cam.sigma_position_m[1] = cam.sigma_position_m[2] = 1.0;
    cam.sigma_rotation_rad[0] = cam.sigma_rotation_rad[1] = cam.sigma_rotation_rad[2] = 0.01;
    const FilteredPose o = f.step(cam, 0, &m);
    if (k < 3) {
      EXPECT_NE(o.flags, 0u);
    }
    if (k >= 10) {
      EXPECT_EQ(o.flags, 0u) << k;
      EXPECT_NEAR(o.sensor.position[0], cam.position[0], 1e-6) << k;
      EXPECT_NEAR(o.sensor.position[1], cam.position[1], 1e-6) << k;
      EXPECT_NEAR(o.sensor.position[2], 1.5, 1e-9);
      EXPECT_NEAR(o.base_position[0], b.x, 1e-6) << k;
    }
  }
}

TEST(OdometryFilter, AFlaggedOrUnconfidentEstimateIsNoMeasurement) {
  OdometryFilterParams p;
  p.filter = params();
  p.estimate_max_radius_m = 10.0;
  OdometryFilter f(p, Eigen::Isometry3d::Identity());
  const PlanarMotion m = step_motion();
  PoseEstimate e;
  e.has_sigma = true;
  e.sigma_position_m[0] = e.sigma_position_m[1] = 20.0;  // 95 % radius ~49 m > 10
  e.sigma_rotation_rad[2] = 0.01;
  for (int k = 0; k < 10; ++k) EXPECT_NE(f.step(e, 0, &m).flags & kPoseUnconfirmed, 0u);
  e.sigma_position_m[0] = e.sigma_position_m[1] = 1.0;
  for (int k = 0; k < 10; ++k) EXPECT_NE(f.step(e, kPoseStaleFrame, &m).flags, 0u);
}

// --- odometry ----------------------------------------------------------------

TEST(Odometry, IntegratesAnArcExactly) {
  std::vector<OdometrySample> s;
  for (int k = 0; k <= 100; ++k) s.push_back({k * kDt, kSpeed, kYawRate});
  auto series = OdometrySeries::from_samples(s, "test");
  ASSERT_TRUE(series);
  PlanarMotion m;
  // From 0.5 s to 2.5 s, across sample boundaries at odd places.
  ASSERT_TRUE(series->motion(0.51, 2.53, &m));
  const double a = kYawRate * 2.02, r = kSpeed / kYawRate;
  EXPECT_NEAR(m.dx, r * std::sin(a), 1e-9);
  EXPECT_NEAR(m.dy, r * (1 - std::cos(a)), 1e-9);
  EXPECT_NEAR(m.dyaw, a, 1e-12);
  EXPECT_NEAR(m.distance_m, kSpeed * 2.02, 1e-9);
}

TEST(Odometry, RefusesWhatItDoesNotCover) {
  std::vector<OdometrySample> s = {{0.0, 5, 0}, {0.1, 5, 0}, {2.0, 5, 0}};
  auto series = OdometrySeries::from_samples(s, "test");
  ASSERT_TRUE(series);
  PlanarMotion m;
  EXPECT_FALSE(series->motion(-0.1, 0.05, &m));  // before the first sample
  EXPECT_TRUE(series->motion(0.0, 0.5, &m));     // held for 0.5 s: still fine
  EXPECT_FALSE(series->motion(0.0, 1.0, &m));    // silent for 0.9 s
  EXPECT_FALSE(series->motion(2.0, 3.0, &m));    // past the last sample
  EXPECT_FALSE(series->motion(1.0, 0.5, &m));    // backwards
}

TEST(Odometry, ParseErrorsNameTheLine) {
  auto ok = OdometrySeries::parse("# seconds speed yaw_rate\n0 1 0\n0.04 1 0.01\n", "o.txt");
  ASSERT_TRUE(ok);
  EXPECT_EQ(ok->size(), 2u);
  const char* bad[] = {"0 1\n", "0 1 0\n0 1 0\n", "0 1 nan\n", "0 400 0\n", "0 1 90\n", "", "#\n"};
  const char* why[] = {"expected", "not after",  "finite",    "metres per second",
                       "radians",  "no samples", "no samples"};
  for (int i = 0; i < 7; ++i) {
    auto r = OdometrySeries::parse(bad[i], "o.txt");
    ASSERT_FALSE(r) << bad[i];
    EXPECT_NE(std::string(r.error().message()).find(why[i]), std::string::npos)
        << r.error().message();
  }
}

// The live track (OdometryTrack) integrates as the file's series does, and
// its gaps and backward stamps begin new epochs, across which there is no
// motion.
TEST(Odometry, ALiveTrackAgreesWithTheSeriesAndBreaksAtGaps) {
  OdometryTrack track;
  std::vector<OdometrySample> s;
  for (int k = 0; k <= 200; ++k) {
    s.push_back({k * 0.01, kSpeed + 0.01 * k, kYawRate * std::sin(0.05 * k)});
    track.add(s.back());
  }
  auto series = OdometrySeries::from_samples(s, "test");
  ASSERT_TRUE(series);
  PlanarMotion from_series, from_track;
  ASSERT_TRUE(series->motion(0.333, 1.777, &from_series));
  ASSERT_TRUE(motion_between(track.at(0.333), track.at(1.777), &from_track));
  EXPECT_NEAR(from_track.dx, from_series.dx, 1e-9);
  EXPECT_NEAR(from_track.dy, from_series.dy, 1e-9);
  EXPECT_NEAR(from_track.dyaw, from_series.dyaw, 1e-12);
  EXPECT_NEAR(from_track.distance_m, from_series.distance_m, 1e-9);
  // Held past the newest sample for 0.5 s at most; nothing before the oldest.
  EXPECT_TRUE(track.at(2.0 + 0.4).valid);
  EXPECT_FALSE(track.at(2.0 + 0.6).valid);
  EXPECT_FALSE(track.at(-0.1).valid);
  // A second of silence: a new epoch, no motion across it.
  track.add({3.5, kSpeed, 0});
  track.add({3.51, kSpeed, 0});
  EXPECT_FALSE(motion_between(track.at(1.9), track.at(3.505), &from_track));
  EXPECT_TRUE(motion_between(track.at(3.5), track.at(3.505), &from_track));
  EXPECT_NEAR(from_track.dx, kSpeed * 0.005, 1e-9);
  // A stamp that goes back: another epoch.
  track.add({3.0, kSpeed, 0});
  EXPECT_FALSE(motion_between(track.at(3.505), track.at(3.1), &from_track));
}

}  // namespace
}  // namespace aprt
