// TwistReader::create() in the program: the reader is made by the DDS module
// (drivers/dds/dds_module.h).
#include "drivers/dds/dds_module.h"
#include "drivers/input/twist/twist_reader.h"

namespace aprt {

Expected<std::unique_ptr<TwistReader>> TwistReader::create(const TwistOptions& o) {
  auto m = open_dds_module();
  if (!m) return m.error();
  return m.value()->create_twist_reader(o);
}

}  // namespace aprt
