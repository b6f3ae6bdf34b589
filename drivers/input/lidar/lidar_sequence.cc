#include "drivers/input/lidar/lidar_sequence.h"

#include <cstdio>
#include <cstring>
#include <new>

#include "runtime/base/check.h"

namespace aprt {

Expected<std::unique_ptr<LidarSequence>> LidarSequence::open(const char* folder) {
  std::unique_ptr<LidarSequence> s(new (std::nothrow) LidarSequence());
  APRT_ENSURE(s != nullptr, Errc::kOutOfMemory, "lidar: out of memory");
  APRT_ENSURE(std::strlen(folder) < sizeof s->folder_ - 1, Errc::kInvalidArgument,
              "lidar: folder path too long");
  std::snprintf(s->folder_, sizeof s->folder_, "%s", folder);
  char path[768];
  std::snprintf(path, sizeof path, "%s/lidar_poses.txt", folder);
  if (Status st = read_pose_list(path, &s->entries_); !st) return st.error();
  auto reader = ScanReader::create();
  if (!reader) return reader.error();
  s->reader_ = std::move(reader.value());
  return s;
}

Status LidarSequence::read(size_t i, const PointRegion& region, PointCloud* cloud) {
  APRT_ENSURE(i < entries_.size(), Errc::kInvalidArgument, "lidar: scan %zu of %zu", i,
              entries_.size());
  char path[768];
  std::snprintf(path, sizeof path, "%s/%s", folder_, entries_[i].name);
  return reader_->read(path, region, cloud);
}

}  // namespace aprt
