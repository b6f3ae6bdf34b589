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

Expected<DdsReader> dds_open_reader(int32_t participant, const void* descriptor,
                                    const std::string& ros_name, bool reliable, int depth) {
  const std::string topic = ros_topic(ros_name);
  const dds_entity_t t =
      dds_create_topic(participant, static_cast<const dds_topic_descriptor_t*>(descriptor),
                       topic.c_str(), nullptr, nullptr);
  if (t < 0) {
    return Error(Errc::kInvalidArgument, "dds: cannot create topic '%s' (from '%s'): %s",
                 topic.c_str(), ros_name.c_str(), dds_strretcode(t));
  }
  dds_qos_t* q = dds_create_qos();
  dds_qset_reliability(q, reliable ? DDS_RELIABILITY_RELIABLE : DDS_RELIABILITY_BEST_EFFORT,
                       DDS_SECS(1));
  dds_qset_history(q, DDS_HISTORY_KEEP_LAST, depth > 0 ? depth : 1);
  DdsReader r;
  r.reader = dds_create_reader(participant, t, q, nullptr);
  dds_delete_qos(q);
  if (r.reader < 0) return dds_failure("create reader", r.reader);
  r.waitset = dds_create_waitset(participant);
  const dds_entity_t rc = dds_create_readcondition(r.reader, DDS_ANY_STATE);
  if (r.waitset < 0 || rc < 0 || dds_waitset_attach(r.waitset, rc, 0) < 0) {
    return dds_failure("create waitset", r.waitset < 0 ? r.waitset : rc);
  }
  return r;
}

int dds_publishers(int32_t reader) {
  dds_subscription_matched_status_t st{};
  return dds_get_subscription_matched_status(reader, &st) == DDS_RETCODE_OK ? int(st.current_count)
                                                                            : 0;
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
