#include "drivers/input/pointcloud2/pointcloud2_source.h"

#include <new>

namespace aprt {

Expected<std::unique_ptr<PointCloud2Source>> PointCloud2Source::create(
    const PointCloud2Options& dds, const ScanSourceOptions& scans) {
  std::unique_ptr<PointCloud2Source> s(new (std::nothrow) PointCloud2Source());
  if (!s) return Error(Errc::kOutOfMemory, "pointcloud2: out of memory");
  auto cloud = PointCloud::create(scans.max_points);
  if (!cloud) return cloud.error();
  auto reader = PointCloud2Reader::create(dds);
  if (!reader) return reader.error();
  s->cloud_ = std::move(cloud.value());
  s->reader_ = std::move(reader.value());
  s->options_ = scans;
  return s;
}

SourceResult PointCloud2Source::next(FrameBuffer* dst, int64_t timeout_ns) {
  int64_t stamp_ns = 0;
  const bool got = reader_->take_latest(options_.region, cloud_.get(), timeout_ns, &stamp_ns);
  const PointCloud2Stats& st = reader_->stats();
  uint64_t refused = 0;
  for (uint64_t r : st.refused) refused += r;
  if (refused != refused_seen_) {  // a malformed cloud: counted, reported, not delivered
    refused_seen_ = refused;
    if (!got) {
      error_ = Error(Errc::kInvalidArgument, "pointcloud2: cloud refused: %s", st.last_refusal);
      return SourceResult::kSkipped;
    }
  }
  if (!got) return SourceResult::kTimeout;
  copy_scan(*cloud_, dst);
  FrameInfo& f = dst->info;
  f.sequence = sequence_++;
  f.capture_ns = monotonic_ns();
  f.source_stamp_ns = stamp_ns;
  f.has_truth = false;
  f.name[0] = '\0';
  return SourceResult::kFrame;
}

}  // namespace aprt
