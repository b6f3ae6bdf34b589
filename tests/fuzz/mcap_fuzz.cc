// libFuzzer target: arbitrary bytes as a recorded drive (`source.type: mcap`):
// the file through McapReader (record walk, schemas, channels, the chosen
// channel's index), then every message of it through the ROS 2 CDR readers
// (Image and PointCloud2), as McapSource reads them. It must refuse or read,
// never crash, read outside a message or allocate without bound.
#include <cstdint>
#include <cstdlib>

#include "drivers/codec/mcap_reader.h"
#include "drivers/codec/ros2_cdr.h"
#include "tests/fuzz/fuzz_file.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  const char* path = aprt::fuzz::write_input(data, size, ".mcap");
  if (!path) return 0;
  auto r =
      aprt::McapReader::open(path, "", {"sensor_msgs/msg/Image", "sensor_msgs/msg/PointCloud2"});
  if (!r) return 0;
  aprt::McapReader& m = *r.value();
  for (size_t i = 0; i < m.size() && i < 64; ++i) {
    size_t n = 0;
    auto bytes = m.read(i, &n);
    if (!bytes) continue;
    if (n > m.max_message_bytes()) std::abort();
    aprt::ros2::ImageMsg img;
    if (aprt::ros2::read_image(bytes.value(), n, &img)) {
      if (img.data + img.size > bytes.value() + n) std::abort();
    }
    aprt::ros2::PointCloud2Msg pc;
    if (aprt::ros2::read_pointcloud2(bytes.value(), n, &pc)) {
      if (pc.data + pc.size > bytes.value() + n || pc.n_fields > pc.kMaxFields) std::abort();
    }
  }
  return 0;
}
