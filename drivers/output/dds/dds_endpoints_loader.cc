// DdsPublisher::create() and DdsListener::create() in the program: the
// endpoints are made by the DDS module (drivers/dds/dds_module.h).
#include "drivers/dds/dds_module.h"
#include "drivers/output/dds/dds_listener.h"
#include "drivers/output/dds/dds_publisher.h"

namespace aprt {

Expected<std::unique_ptr<DdsPublisher>> DdsPublisher::create(const DdsOptions& o) {
  auto m = open_dds_module();
  if (!m) return m.error();
  return m.value()->create_publisher(o);
}

Expected<std::unique_ptr<DdsListener>> DdsListener::create(const DdsOptions& o) {
  auto m = open_dds_module();
  if (!m) return m.error();
  return m.value()->create_listener(o);
}

}  // namespace aprt
