#include "runtime/loop/run_report.h"

#include <algorithm>
#include <cstdio>

namespace aprt {

double quantile(std::vector<double> v, double p) {
  if (v.empty()) return 0;
  std::sort(v.begin(), v.end());
  return v[std::min(v.size() - 1, size_t(p * double(v.size() - 1) + 0.5))];
}

void print_run_summary(const RunSummary& s) {
  const RunStats& st = *s.stats;
  std::vector<double> infer, e2e;
  for (size_t i = 0; i < s.timing_count; ++i) {
    const TimingRecord& t = s.timings[i];
    infer.push_back(double(t.inference_end_ns - t.inference_start_ns) * 1e-6);
    e2e.push_back(double(t.publish_ns - t.capture_ns) * 1e-6);
  }
  std::printf(
      "\nsummary: %llu frames captured, %llu skipped, %llu dropped as stale by the slot; "
      "%llu poses (%llu flagged), %llu deadline misses\n",
      static_cast<unsigned long long>(st.frames_captured),
      static_cast<unsigned long long>(st.frames_skipped),
      static_cast<unsigned long long>(st.frames_dropped), static_cast<unsigned long long>(st.poses),
      static_cast<unsigned long long>(st.poses_flagged),
      static_cast<unsigned long long>(st.deadline_misses));
  if (!infer.empty()) {
    std::printf(
        "latency: inference median %.1f ms p99 %.1f ms max %.1f ms; capture to publish "
        "median %.1f ms p99 %.1f ms max %.1f ms (%s kernels, %d thread%s)\n",
        quantile(infer, 0.5), quantile(infer, 0.99), quantile(infer, 1.0), quantile(e2e, 0.5),
        quantile(e2e, 0.99), quantile(e2e, 1.0), s.isa, s.threads, s.threads == 1 ? "" : "s");
    if (s.timing_count < st.poses) {
      std::printf("  (latency and errors of the first %zu poses: output.records is full)\n",
                  s.timing_count);
    }
  }
  if (s.lidar) {
    std::printf("lidar: %llu of %llu scans too sparse for the model (flagged)\n",
                static_cast<unsigned long long>(st.sparse_scans),
                static_cast<unsigned long long>(st.poses));
  }
  if (s.camera_names.size() > 1) {
    std::printf("fusion: %zu cameras; %llu of %llu cycles without a quorum\n",
                s.camera_names.size(), static_cast<unsigned long long>(st.fusion_no_quorum),
                static_cast<unsigned long long>(st.poses));
    for (size_t i = 0; i < s.camera_names.size() && i < st.cameras.size(); ++i) {
      const RunStats::Camera& c = st.cameras[i];
      std::printf(
          "  camera %s: %llu frames, %llu dropped as stale, %llu cycles without a frame in time, "
          "%llu estimates flagged, %llu rejected as outliers\n",
          s.camera_names[i].c_str(), static_cast<unsigned long long>(c.frames),
          static_cast<unsigned long long>(c.dropped), static_cast<unsigned long long>(c.missing),
          static_cast<unsigned long long>(c.flagged), static_cast<unsigned long long>(c.outliers));
    }
  }
  if (s.error_count > 0) {
    std::vector<double> pe(s.position_errors, s.position_errors + s.error_count);
    std::vector<double> re(s.orientation_errors, s.orientation_errors + s.error_count);
    double ps = 0, rs = 0;
    for (double v : pe) ps += v;
    for (double v : re) rs += v;
    std::printf(
        "errors against ground truth: position median %.2f m, mean %.2f m, p90 %.2f m; "
        "orientation median %.2f deg, mean %.2f deg, p90 %.2f deg\n",
        quantile(pe, 0.5), ps / double(pe.size()), quantile(pe, 0.9), quantile(re, 0.5),
        rs / double(re.size()), quantile(re, 0.9));
  }
  if (s.memory && s.memory[0]) std::printf("memory: %s\n", s.memory);
}

}  // namespace aprt
