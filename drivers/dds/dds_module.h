// The DDS endpoints live in a module, aprt_dds.so, opened by the first
// create() of a DdsPublisher, DdsListener or PointCloud2Reader
// (dds_loader.cc). Cyclone DDS brings OpenSSL and iceoryx with it, ~3 MiB
// resident once relocated: `aprt bench`, `aprt eval`, a CAN-only vehicle
// load none of it. This table is the module's whole interface; the module is
// built from the same sources and compiler as the program, so C++ types
// cross it (drivers/module/driver_module.h).
#pragma once

#include <cstdint>
#include <memory>

#include "runtime/base/expected.h"

namespace aprt {

// drivers/output/dds/dds_publisher.h, dds_listener.h,
// drivers/input/pointcloud2/pointcloud2_reader.h and
// drivers/input/twist/twist_reader.h.
class DdsPublisher;
class DdsListener;
class PointCloud2Reader;
class TwistReader;
struct DdsOptions;
struct PointCloud2Options;
struct TwistOptions;

struct DdsModuleApi {
  static constexpr uint32_t kAbi = 2;  // bumped with any change to this struct or the classes
  uint32_t abi = kAbi;
  Expected<std::unique_ptr<DdsPublisher>> (*create_publisher)(const DdsOptions&) = nullptr;
  Expected<std::unique_ptr<DdsListener>> (*create_listener)(const DdsOptions&) = nullptr;
  Expected<std::unique_ptr<PointCloud2Reader>> (*create_pointcloud2_reader)(
      const PointCloud2Options&) = nullptr;
  Expected<std::unique_ptr<TwistReader>> (*create_twist_reader)(const TwistOptions&) = nullptr;
};

// The module's one exported symbol.
#define APRT_DDS_MODULE_SYMBOL "aprt_dds_module"
using DdsModuleEntry = const DdsModuleApi* (*)();

// The table, the module opened once (from $APRT_DDS_MODULE or ../lib/aprt/
// beside the executable) and never closed: Cyclone's threads run its code
// until the process ends. For the endpoints' create().
Expected<const DdsModuleApi*> open_dds_module();

// Inside the module: the Cyclone DDS implementations (dds_publisher.cc,
// dds_listener.cc, pointcloud2_reader.cc).
Expected<std::unique_ptr<DdsPublisher>> create_cyclone_publisher(const DdsOptions& o);
Expected<std::unique_ptr<DdsListener>> create_cyclone_listener(const DdsOptions& o);
Expected<std::unique_ptr<PointCloud2Reader>> create_cyclone_pointcloud2_reader(
    const PointCloud2Options& o);
Expected<std::unique_ptr<TwistReader>> create_cyclone_twist_reader(const TwistOptions& o);

}  // namespace aprt
