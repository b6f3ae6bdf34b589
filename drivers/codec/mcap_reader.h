// Reading the messages of one channel of an MCAP file (https://mcap.dev/spec)
// in file order: what `source.type: mcap` replays. Unchunked files (what
// aprt and `ros2 bag record --storage mcap` without compression write) are
// read record by record; chunked or compressed files are refused with the
// reason, as are records that run past the end.
//
// open() walks the record headers once (bounded I/O: pread of 9 bytes per
// record plus the schemas and channels), keeps the offset and log time of
// each message of the chosen channel, and sizes one buffer for the largest;
// read() then costs one pread and allocates nothing. A file cut short (a
// recording that lost power) keeps its whole records; open() says so.
#pragma once

#include <cstddef>
#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "runtime/base/expected.h"

namespace aprt {

struct McapChannelInfo {
  uint16_t id = 0;
  std::string topic, schema_name, message_encoding;
  uint64_t messages = 0;
};

class McapReader {
 public:
  // `topic` empty: the first channel whose schema is one of `schemas`
  // (e.g. {"sensor_msgs/msg/Image", "sensor_msgs/msg/PointCloud2"}).
  static Expected<std::unique_ptr<McapReader>> open(const char* path, const std::string& topic,
                                                    const std::vector<std::string>& schemas);
  ~McapReader();
  McapReader(const McapReader&) = delete;
  McapReader& operator=(const McapReader&) = delete;

  const McapChannelInfo& channel() const { return channel_; }
  const std::vector<McapChannelInfo>& channels() const { return channels_; }
  size_t size() const { return offsets_.size(); }
  uint64_t log_time_ns(size_t i) const { return log_times_[i]; }
  size_t max_message_bytes() const { return max_bytes_; }
  bool truncated() const { return truncated_; }  // the file ends inside a record
  // Message i's bytes (valid until the next read()).
  Expected<const uint8_t*> read(size_t i, size_t* size);

 private:
  McapReader() = default;
  int fd_ = -1;
  std::string path_;
  McapChannelInfo channel_;
  std::vector<McapChannelInfo> channels_;
  std::vector<uint64_t> offsets_;    // of each message's data
  std::vector<uint32_t> sizes_;      // its data bytes
  std::vector<uint64_t> log_times_;  // ns
  std::unique_ptr<uint8_t[]> buf_;
  size_t max_bytes_ = 0;
  bool truncated_ = false;
};

}  // namespace aprt
