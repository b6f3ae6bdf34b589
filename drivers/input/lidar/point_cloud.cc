#include "drivers/input/lidar/point_cloud.h"

#include <cmath>
#include <cstdlib>
#include <cstring>
#include <new>

namespace aprt {

Expected<std::unique_ptr<PointCloud>> PointCloud::create(size_t capacity) {
  if (capacity == 0 || capacity > (size_t(1) << 24)) {
    return Error(Errc::kInvalidArgument, "lidar: a scan buffer of %zu points is out of range",
                 capacity);
  }
  std::unique_ptr<PointCloud> c(new (std::nothrow) PointCloud());
  if (!c) return Error(Errc::kOutOfMemory, "lidar: out of memory");
  c->points_ =
      static_cast<Point*>(std::aligned_alloc(64, (capacity * sizeof(Point) + 63) / 64 * 64));
  if (!c->points_) return Error(Errc::kOutOfMemory, "lidar: cannot allocate %zu points", capacity);
  c->capacity_ = capacity;
  return c;
}

PointCloud::~PointCloud() {
  std::free(points_);
}

void PointCloud::add(float x, float y, float z, float intensity) noexcept {
  ++stats_.read;
  if (!std::isfinite(x) || !std::isfinite(y) || !std::isfinite(z)) {
    ++stats_.non_finite;
    return;
  }
  if (size_ == capacity_) {
    ++stats_.over_capacity;
    return;
  }
  const PointRegion& r = region_;
  const float cx = x < r.x_min ? r.x_min : (x > r.x_max ? r.x_max : x);
  const float cy = y < r.y_min ? r.y_min : (y > r.y_max ? r.y_max : y);
  const float cz = z < r.z_min ? r.z_min : (z > r.z_max ? r.z_max : z);
  if (cx != x || cy != y || cz != z) ++stats_.clipped;
  points_[size_++] = {cx, cy, cz, std::isfinite(intensity) ? intensity : 0.0f};
}

void copy_scan(const PointCloud& cloud, FrameBuffer* dst) {
  const size_t n = cloud.size();
  std::memcpy(dst->data, cloud.points(), n * sizeof(Point));
  FrameInfo& f = dst->info;
  f.kind = FrameKind::kScan;
  f.width = int(n);
  f.height = 1;
  f.stride = n * sizeof(Point);
  f.bytes = n * sizeof(Point);
  const ScanStats& s = cloud.stats();
  f.scan.points = uint32_t(n);
  f.scan.non_finite = uint32_t(s.non_finite);
  f.scan.clipped = uint32_t(s.clipped);
  f.scan.over_capacity = uint32_t(s.over_capacity);
}

}  // namespace aprt
