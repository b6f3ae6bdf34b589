// The entry point of aprt_dds.so (dds_module.h). Everything else in the
// module is hidden, so its copy of aprt's base code never meets the program's.
#include "drivers/dds/dds_module.h"

extern "C" __attribute__((visibility("default"))) const aprt::DdsModuleApi* aprt_dds_module() {
  static const aprt::DdsModuleApi api{
      aprt::DdsModuleApi::kAbi, aprt::create_cyclone_publisher, aprt::create_cyclone_listener,
      aprt::create_cyclone_pointcloud2_reader, aprt::create_cyclone_twist_reader};
  return &api;
}
