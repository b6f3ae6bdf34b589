// What every DDS endpoint of aprt shares (the pose publisher, the PointCloud2
// reader, the listener tools): joining a domain -- with the loopback-only
// profile if asked -- ROS 2's topic naming, and Cyclone's return codes as
// errors. The Cyclone DDS headers stay inside the .cc files.
#pragma once

#include <cstdint>
#include <string>

#include "runtime/base/expected.h"

namespace aprt {

// The Cyclone DDS configuration of the loopback-only profile: interface lo,
// no multicast, peer 127.0.0.1, participant indices raised past 10 per host.
std::string dds_loopback_config(uint32_t domain);

// "rt" + the ROS name ("/aprt/pose" -> "rt/aprt/pose"; a missing leading
// slash is added), as rmw_cyclonedds names topics.
std::string ros_topic(const std::string& ros_name);

// A participant on `domain` (with the loopback profile when loopback_only);
// *domain_handle is the domain entity created for the profile (0 if none), to
// be deleted with the participant.
Expected<int32_t> dds_join(uint32_t domain, bool loopback_only, int32_t* domain_handle);

// "dds: WHAT failed: <Cyclone's reason>".
Error dds_failure(const char* what, int32_t rc);

// A reader of the ROS 2 topic `ros_name` with the generated type `descriptor`
// (a dds_topic_descriptor_t, opaque here): reliable or best effort,
// keep-last `depth`, and a waitset that wakes on its samples (the inputs:
// PointCloud2, the vehicle's twist).
struct DdsReader {
  int32_t reader = 0, waitset = 0;
};
Expected<DdsReader> dds_open_reader(int32_t participant, const void* descriptor,
                                    const std::string& ros_name, bool reliable, int depth);
// Writers matched with `reader` right now.
int dds_publishers(int32_t reader);

}  // namespace aprt
