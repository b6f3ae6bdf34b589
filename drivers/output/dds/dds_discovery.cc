#include "drivers/output/dds/dds_discovery.h"

#include <dds/dds.h>

#include <cstring>
#include <ctime>

namespace aprt {
namespace {

int64_t monotonic_now_ns() {
  timespec ts{};
  clock_gettime(CLOCK_MONOTONIC, &ts);
  return int64_t(ts.tv_sec) * 1000000000 + ts.tv_nsec;
}

// A fixed set of GUIDs: discovery on one domain, a few dozen participants at most
// in a vehicle; more than kMax are not waited for (the wait stays bounded anyway).
struct GuidSet {
  static constexpr int kMax = 128;
  dds_guid_t g[kMax];
  int n = 0;
  bool has(const dds_guid_t& x) const {
    for (int i = 0; i < n; ++i)
      if (std::memcmp(g[i].v, x.v, sizeof x.v) == 0) return true;
    return false;
  }
  bool add(const dds_guid_t& x) {  // true when new
    if (has(x) || n == kMax) return false;
    g[n++] = x;
    return true;
  }
};

// Reads (without taking) what a built-in reader holds; calls f on each valid sample.
template <typename Sample, typename F>
void read_all(dds_entity_t reader, F&& f) {
  constexpr int kBatch = 64;
  void* buf[kBatch] = {};
  dds_sample_info_t info[kBatch];
  const int n = dds_read(reader, buf, info, kBatch, kBatch);
  if (n <= 0) return;
  for (int i = 0; i < n; ++i)
    if (info[i].valid_data && info[i].instance_state == DDS_ALIVE_INSTANCE_STATE)
      f(*static_cast<const Sample*>(buf[i]));
  dds_return_loan(reader, buf, n);
}

}  // namespace

DdsDiscoveryReport settle_discovery(int32_t participant, int64_t max_wait_ns, int64_t quiet_ns) {
  DdsDiscoveryReport r;
  if (max_wait_ns <= 0) return r;
  dds_guid_t self{};
  if (dds_get_guid(participant, &self) != DDS_RETCODE_OK) return r;
  const dds_entity_t parts =
      dds_create_reader(participant, DDS_BUILTIN_TOPIC_DCPSPARTICIPANT, nullptr, nullptr);
  const dds_entity_t pubs =
      dds_create_reader(participant, DDS_BUILTIN_TOPIC_DCPSPUBLICATION, nullptr, nullptr);
  const dds_entity_t subs =
      dds_create_reader(participant, DDS_BUILTIN_TOPIC_DCPSSUBSCRIPTION, nullptr, nullptr);
  const int64_t start = monotonic_now_ns();
  int64_t last_news = start;
  GuidSet peers, with_endpoints;
  if (parts > 0 && pubs > 0 && subs > 0) {
    for (;;) {
      const int64_t now = monotonic_now_ns();
      read_all<dds_builtintopic_participant_t>(parts, [&](const auto& p) {
        if (std::memcmp(p.key.v, self.v, sizeof self.v) != 0 && peers.add(p.key)) last_news = now;
      });
      auto endpoint = [&](const dds_builtintopic_endpoint_t& e) {
        if (with_endpoints.add(e.participant_key)) last_news = now;
      };
      read_all<dds_builtintopic_endpoint_t>(pubs, endpoint);
      read_all<dds_builtintopic_endpoint_t>(subs, endpoint);
      int pending = 0;
      for (int i = 0; i < peers.n; ++i) pending += with_endpoints.has(peers.g[i]) ? 0 : 1;
      r.participants = peers.n;
      r.pending = pending;
      if (pending == 0 && now - last_news >= quiet_ns) break;
      if (now - start >= max_wait_ns) break;
      const timespec tick{0, 10000000};  // 10 ms
      nanosleep(&tick, nullptr);
    }
  }
  r.waited_ns = monotonic_now_ns() - start;
  // The built-in readers would keep every endpoint of the network for the run: gone.
  if (parts > 0) dds_delete(parts);
  if (pubs > 0) dds_delete(pubs);
  if (subs > 0) dds_delete(subs);
  return r;
}

}  // namespace aprt
