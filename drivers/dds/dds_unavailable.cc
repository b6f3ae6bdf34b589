// Built instead of dds_domain.cc when Cyclone DDS is not
// found for the target.
#include "drivers/dds/dds_domain.h"

namespace aprt {

std::string dds_loopback_config(uint32_t) {
  return "";
}

std::string ros_topic(const std::string& ros_name) {
  return "rt" + ros_name;
}

Error dds_failure(const char* what, int32_t) {
  return Error(Errc::kUnsupported, "dds: %s: this build has no DDS", what);
}

Expected<int32_t> dds_join(uint32_t, bool, int32_t* domain_handle) {
  *domain_handle = 0;
  return dds_failure("join", 0);
}

}  // namespace aprt
