#include "runtime/loop/timing_report.h"

#include <gtest/gtest.h>
#include <unistd.h>

#include <cstdio>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

#include "runtime/loop/runtime.h"

namespace aprt {
namespace {

std::string slurp(const std::string& path) {
  std::ifstream f(path);
  std::stringstream s;
  s << f.rdbuf();
  return s.str();
}

TEST(TimingReport, StageStatistics) {
  std::vector<double> v;
  for (int i = 1000; i >= 1; --i) v.push_back(double(i));  // 1..1000 ms, unsorted
  const StageStats s = stage_stats(v.data(), v.size());
  EXPECT_EQ(s.count, 1000u);
  EXPECT_DOUBLE_EQ(s.min, 1);
  EXPECT_DOUBLE_EQ(s.max, 1000);
  EXPECT_NEAR(s.median, 500.5, 0.5);
  EXPECT_NEAR(s.p99, 990, 1);
  EXPECT_NEAR(s.p999, 999, 1);
  EXPECT_DOUBLE_EQ(s.mean, 500.5);
  const StageStats none = stage_stats(nullptr, 0);
  EXPECT_EQ(none.count, 0u);
}

TEST(TimingReport, WritesJsonAndCsv) {
  std::vector<TimingRecord> t;
  for (int i = 0; i < 100; ++i) {
    const int64_t c = int64_t(i) * 100000000;  // 10 Hz
    t.push_back({c, c + 1000000, c + 21000000, c + 22000000 + (i == 99 ? 30000000 : 0), 0});
  }
  RunStats st;
  st.frames_captured = st.poses = 100;
  st.deadline_misses = 1;
  TimingContext ctx;
  ctx.model = "m\"odel.aprt";  // escaped in the JSON
  ctx.source = "replay";
  ctx.isa = "ref";
  ctx.camera_period_ms = 100;
  ctx.allocations_counted = true;
  ctx.steady = {true, 10, 1000};
  ctx.end = {true, 10, 1004};
  char dir[] = "/tmp/aprt_timing_XXXXXX";
  ASSERT_NE(mkdtemp(dir), nullptr);
  const std::string json = std::string(dir) + "/report.json";
  ASSERT_TRUE(write_timing_report(json.c_str(), t.data(), t.size(), st, ctx));
  const std::string j = slurp(json);
  EXPECT_NE(j.find("\"model\": \"m\\\"odel.aprt\""), std::string::npos) << j;
  EXPECT_NE(j.find("\"inference\": {\"count\": 100, \"min\": 20.000, \"median\": 20.000"),
            std::string::npos)
      << j;
  EXPECT_NE(j.find("\"max\": 52.000}"), std::string::npos) << j;  // the one late publish
  EXPECT_NE(j.find("\"allocations_after_first_pose\": 0"), std::string::npos) << j;
  EXPECT_NE(j.find("\"rss_growth_kb\": 4"), std::string::npos) << j;
  EXPECT_NE(j.find("\"within_bound\": true"), std::string::npos) << j;  // 52 <= 1.05*22 + 100
  const std::string c = slurp(std::string(dir) + "/report.csv");
  EXPECT_EQ(c.rfind("index,capture_ns,", 0), 0u);
  EXPECT_NE(c.find("\n99,9900000000,9901000000,9921000000,9952000000\n"), std::string::npos);
  std::remove(json.c_str());
  std::remove((std::string(dir) + "/report.csv").c_str());
  rmdir(dir);
}

TEST(TimingReport, UnwritablePathIsAnError) {
  TimingRecord t{0, 1, 2, 3, 0};
  RunStats st;
  TimingContext ctx;
  auto s = write_timing_report("/nonexistent-dir/r.json", &t, 1, st, ctx);
  ASSERT_FALSE(s);
  EXPECT_NE(std::string(s.error().message()).find("cannot write /nonexistent-dir/r.json"),
            std::string::npos);
}

TEST(TimingReport, ResidentSetIsReadable) {
  EXPECT_GT(current_rss_kb(), 0u);
  EXPECT_GT(peak_rss_kb(), 0u);
}

}  // namespace
}  // namespace aprt
