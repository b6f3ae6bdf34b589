// The program's side of the DDS module (dds_module.h): opened once, checked
// against this program's interface.
#include "drivers/dds/dds_module.h"
#include "drivers/module/driver_module.h"

namespace aprt {
namespace {

struct Module {
  const DdsModuleApi* api = nullptr;
  Error error;
};

Module load_module() {
  Module m;
  auto entry = open_driver_module("APRT_DDS_MODULE", "aprt_dds.so", APRT_DDS_MODULE_SYMBOL, "dds",
                                  "is aprt installed whole? set APRT_DDS_MODULE, or configure "
                                  "no DDS output");
  if (!entry) {
    m.error = entry.error();
    return m;
  }
  const DdsModuleApi* api = reinterpret_cast<DdsModuleEntry>(entry.value())();
  if (!api || api->abi != DdsModuleApi::kAbi) {
    m.error = Error(Errc::kUnsupported,
                    "dds: the DDS module is not this aprt's (another interface version); "
                    "reinstall aprt");
    return m;
  }
  m.api = api;
  return m;
}

}  // namespace

Expected<const DdsModuleApi*> open_dds_module() {
  static const Module m = load_module();  // once, thread-safe
  if (!m.api) return m.error;
  return m.api;
}

}  // namespace aprt
