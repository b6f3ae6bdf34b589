// Start-up discovery for the pose writer: before aprt publishes its first
// pose, wait (bounded) until every participant already in the domain has told
// its endpoints, so a reader that is already running receives the first pose.
//
// Why: DDS delivers a volatile sample only to the readers the writer knows
// when it writes. Finding a participant (SPDP) takes milliseconds; learning
// its readers (SEDP) can take one heartbeat period of the peer's discovery
// writers: Fast DDS 2.9, already running when aprt starts, answers aprt's
// first discovery exchange on loopback only with its 1 s heartbeat, and a
// reader of it missed the first 15-25 poses (measured, docs/outputs.md).
// Not on the real-time path: called once from DdsPublisher::create().
#pragma once

#include <cstdint>

namespace aprt {

struct DdsDiscoveryReport {
  int participants = 0;  // other participants found in the domain
  int pending = 0;       // of those, without a known endpoint when the wait ended
  int64_t waited_ns = 0;
};

// Reads the built-in participant / publication / subscription topics of
// `participant` until each other participant has at least one endpoint known
// and `quiet_ns` passed without news, or until `max_wait_ns`. 0: no wait.
DdsDiscoveryReport settle_discovery(int32_t participant, int64_t max_wait_ns,
                                    int64_t quiet_ns = 100000000);

}  // namespace aprt
