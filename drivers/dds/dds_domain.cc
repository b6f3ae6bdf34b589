#include "drivers/dds/dds_domain.h"

#include <dds/dds.h>

#include <cstdio>

namespace aprt {

std::string dds_loopback_config(uint32_t domain) {
  char buf[768];
  std::snprintf(buf, sizeof buf,
                "<CycloneDDS><Domain Id=\"%u\"><General><Interfaces><NetworkInterface "
                "name=\"lo\"/></Interfaces><AllowMulticast>false</AllowMulticast></General>"
                "<Discovery><ParticipantIndex>auto</ParticipantIndex><MaxAutoParticipantIndex>"
                "120</MaxAutoParticipantIndex><Peers><Peer address=\"127.0.0.1\"/></Peers>"
                "</Discovery></Domain></CycloneDDS>",
                domain);
  return buf;
}

std::string ros_topic(const std::string& name) {
  return "rt" + (!name.empty() && name[0] == '/' ? name : "/" + name);
}

Error dds_failure(const char* what, int32_t rc) {
  return Error(Errc::kIo, "dds: %s failed: %s", what, dds_strretcode(rc));
}

Expected<int32_t> dds_join(uint32_t domain, bool loopback_only, int32_t* domain_handle) {
  *domain_handle = 0;
  if (loopback_only) {
    const std::string xml = dds_loopback_config(domain);
    const dds_entity_t d = dds_create_domain(domain, xml.c_str());
    // PRECONDITION_NOT_MET: this process already created the domain (another endpoint).
    if (d < 0 && d != DDS_RETCODE_PRECONDITION_NOT_MET) return dds_failure("create domain", d);
    *domain_handle = d > 0 ? d : 0;
  }
  const dds_entity_t participant = dds_create_participant(domain, nullptr, nullptr);
  if (participant < 0) return dds_failure("create participant", participant);
  return int32_t(participant);
}

}  // namespace aprt
