// MCAP (https://mcap.dev/spec, major version 0) files written the way
// `ros2 bag record` writes them (profile "ros2", schemas "ros2msg", messages
// "cdr"), so `ros2 bag`, Foxglove and the mcap tools open what aprt records.
//
// Unchunked: the data section is the header, the schemas and channels, and
// one Message record per message in the order written; close() appends the
// summary (schemas, channels, statistics) with its offsets, the footer and the
// closing magic. Readers that need an index read such files linearly; a file
// cut short (power loss) keeps every whole record before the cut.
//
// Allocation-free after create(): records are assembled in a fixed buffer
// and written with write(2); one larger than the buffer goes straight out.
// Not thread-safe: one writer thread (the recorder's) owns it.
#pragma once

#include <cstddef>
#include <cstdint>
#include <memory>

#include "runtime/base/expected.h"

namespace aprt {

class McapWriter {
 public:
  static constexpr int kMaxSchemas = 16;
  static constexpr int kMaxChannels = 16;

  // Creates (truncates) `path`; writes the magic and the header record.
  static Expected<std::unique_ptr<McapWriter>> create(const char* path, const char* library);
  ~McapWriter();  // closes the file (without the summary when close() was not called)
  McapWriter(const McapWriter&) = delete;
  McapWriter& operator=(const McapWriter&) = delete;

  // A message definition (`data`, ros2msg text with its dependencies) under
  // `name` ("sensor_msgs/msg/Image"). `data` must outlive the writer (the
  // summary repeats it): the definitions are static text. Ids from 1.
  Expected<uint16_t> add_schema(const char* name, const char* encoding, const char* data);
  // A topic ("/aprt/pose_with_covariance") carrying `schema`'s messages.
  Expected<uint16_t> add_channel(uint16_t schema, const char* topic, const char* message_encoding);
  // One message; `log_ns` and `publish_ns` since the Unix epoch.
  Status write_message(uint16_t channel, uint64_t log_ns, uint64_t publish_ns, const void* data,
                       size_t size) noexcept;
  // Data end, summary, summary offsets, footer, magic; then the file is closed.
  Status close() noexcept;

  uint64_t messages() const { return message_count_; }
  uint64_t bytes_written() const { return offset_ + used_; }

 private:
  McapWriter() = default;
  Status flush() noexcept;
  Status put(const void* p, size_t n) noexcept;
  Status u8(uint8_t v) noexcept { return put(&v, 1); }
  Status u16(uint16_t v) noexcept { return put(&v, 2); }
  Status u32(uint32_t v) noexcept { return put(&v, 4); }
  Status u64(uint64_t v) noexcept { return put(&v, 8); }
  Status str(const char* s) noexcept;
  Status record(uint8_t op, uint64_t length) noexcept { return put_header(op, length); }
  Status put_header(uint8_t op, uint64_t length) noexcept;
  Status schema_record(int i) noexcept;
  Status channel_record(int i) noexcept;

  int fd_ = -1;
  bool closed_ = false;
  static constexpr size_t kBuffer = 64 * 1024;
  std::unique_ptr<uint8_t[]> buf_;
  size_t used_ = 0;
  uint64_t offset_ = 0;  // bytes already in the file
  uint32_t crc_ = 0;     // of everything before the DataEnd record
  struct Schema {
    char name[96];
    char encoding[16];
    const char* data;
  } schemas_[kMaxSchemas] = {};
  struct Channel {
    uint16_t schema;
    char topic[96];
    char encoding[16];
    uint64_t messages;
    uint32_t sequence;
  } channels_[kMaxChannels] = {};
  int schema_count_ = 0, channel_count_ = 0;
  uint64_t message_count_ = 0, first_ns_ = 0, last_ns_ = 0;
};

}  // namespace aprt
