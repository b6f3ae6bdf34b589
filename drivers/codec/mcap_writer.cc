#include "drivers/codec/mcap_writer.h"

#include <fcntl.h>
#include <unistd.h>

#include <cerrno>
#include <cstdio>
#include <cstring>
#include <new>

#include "runtime/base/crc32.h"

namespace aprt {
namespace {

constexpr uint8_t kMagic[8] = {0x89, 'M', 'C', 'A', 'P', '0', '\r', '\n'};
enum : uint8_t {
  kHeader = 0x01,
  kFooter = 0x02,
  kSchema = 0x03,
  kChannel = 0x04,
  kMessage = 0x05,
  kStatistics = 0x0B,
  kSummaryOffset = 0x0E,
  kDataEnd = 0x0F,
};

uint64_t slen(const char* s) {
  return 4 + std::strlen(s);
}

bool copy(char* dst, size_t cap, const char* src) {
  const size_t n = std::strlen(src);
  if (n >= cap) return false;
  std::memcpy(dst, src, n + 1);
  return true;
}

}  // namespace

Expected<std::unique_ptr<McapWriter>> McapWriter::create(const char* path, const char* library) {
  std::unique_ptr<McapWriter> w(new (std::nothrow) McapWriter());
  if (!w) return Error(Errc::kOutOfMemory, "mcap: out of memory");
  w->buf_.reset(new (std::nothrow) uint8_t[kBuffer]);
  if (!w->buf_) return Error(Errc::kOutOfMemory, "mcap: out of memory");
  w->fd_ = open(path, O_WRONLY | O_CREAT | O_TRUNC | O_CLOEXEC, 0644);
  if (w->fd_ < 0) {
    return Error(Errc::kIo, "mcap: cannot create %s: %s", path, std::strerror(errno));
  }
  Status s = w->put(kMagic, sizeof kMagic);
  if (s) s = w->record(kHeader, slen("ros2") + slen(library));
  if (s) s = w->str("ros2");
  if (s) s = w->str(library);
  if (!s) return s.error();
  return w;
}

McapWriter::~McapWriter() {
  if (fd_ >= 0) {
    (void)flush();
    ::close(fd_);
  }
}

Status McapWriter::flush() noexcept {
  size_t done = 0;
  while (done < used_) {
    const ssize_t n = ::write(fd_, buf_.get() + done, used_ - done);
    if (n < 0 && errno == EINTR) continue;
    if (n <= 0) {
      used_ = 0;
      return Error(Errc::kIo, "mcap: write failed: %s", std::strerror(errno));
    }
    done += size_t(n);
  }
  offset_ += used_;
  used_ = 0;
  return ok();
}

Status McapWriter::put(const void* p, size_t n) noexcept {
  crc_ = crc32(p, n, crc_);
  if (used_ + n > kBuffer) {
    if (Status s = flush(); !s) return s;
  }
  if (n > kBuffer) {  // a large message: straight to the file
    const uint8_t* b = static_cast<const uint8_t*>(p);
    size_t done = 0;
    while (done < n) {
      const ssize_t k = ::write(fd_, b + done, n - done);
      if (k < 0 && errno == EINTR) continue;
      if (k <= 0) return Error(Errc::kIo, "mcap: write failed: %s", std::strerror(errno));
      done += size_t(k);
    }
    offset_ += n;
    return ok();
  }
  std::memcpy(buf_.get() + used_, p, n);
  used_ += n;
  return ok();
}

Status McapWriter::str(const char* s) noexcept {
  const uint32_t n = uint32_t(std::strlen(s));
  if (Status st = u32(n); !st) return st;
  return put(s, n);
}

Status McapWriter::put_header(uint8_t op, uint64_t length) noexcept {
  if (Status s = u8(op); !s) return s;
  return u64(length);
}

Expected<uint16_t> McapWriter::add_schema(const char* name, const char* encoding,
                                          const char* data) {
  if (closed_) return Error(Errc::kInvalidArgument, "mcap: the file is closed");
  if (schema_count_ == kMaxSchemas) {
    return Error(Errc::kInvalidArgument, "mcap: more than %d schemas", kMaxSchemas);
  }
  Schema& s = schemas_[schema_count_];
  if (!copy(s.name, sizeof s.name, name) || !copy(s.encoding, sizeof s.encoding, encoding)) {
    return Error(Errc::kInvalidArgument, "mcap: schema name '%s' or encoding too long", name);
  }
  s.data = data;
  if (Status st = schema_record(schema_count_); !st) return st.error();
  return uint16_t(++schema_count_);
}

Status McapWriter::schema_record(int i) noexcept {
  const Schema& s = schemas_[i];
  Status st = record(kSchema, 2 + slen(s.name) + slen(s.encoding) + slen(s.data));
  if (st) st = u16(uint16_t(i + 1));
  if (st) st = str(s.name);
  if (st) st = str(s.encoding);
  if (st) st = str(s.data);  // bytes: u32 length + the text, as a string is
  return st;
}

Expected<uint16_t> McapWriter::add_channel(uint16_t schema, const char* topic,
                                           const char* message_encoding) {
  if (closed_) return Error(Errc::kInvalidArgument, "mcap: the file is closed");
  if (schema == 0 || schema > schema_count_) {
    return Error(Errc::kInvalidArgument, "mcap: channel %s: no schema %u", topic, schema);
  }
  if (channel_count_ == kMaxChannels) {
    return Error(Errc::kInvalidArgument, "mcap: more than %d channels", kMaxChannels);
  }
  Channel& c = channels_[channel_count_];
  if (!copy(c.topic, sizeof c.topic, topic) ||
      !copy(c.encoding, sizeof c.encoding, message_encoding)) {
    return Error(Errc::kInvalidArgument, "mcap: channel topic '%s' or encoding too long", topic);
  }
  c.schema = schema;
  if (Status st = channel_record(channel_count_); !st) return st.error();
  return uint16_t(++channel_count_);
}

Status McapWriter::channel_record(int i) noexcept {
  const Channel& c = channels_[i];
  Status st = record(kChannel, 2 + 2 + slen(c.topic) + slen(c.encoding) + 4);
  if (st) st = u16(uint16_t(i + 1));
  if (st) st = u16(c.schema);
  if (st) st = str(c.topic);
  if (st) st = str(c.encoding);
  if (st) st = u32(0);  // metadata: an empty map
  return st;
}

Status McapWriter::write_message(uint16_t channel, uint64_t log_ns, uint64_t publish_ns,
                                 const void* data, size_t size) noexcept {
  if (closed_) return Error(Errc::kInvalidArgument, "mcap: the file is closed");
  if (channel == 0 || channel > channel_count_) {
    return Error(Errc::kInvalidArgument, "mcap: no channel %u", channel);
  }
  Channel& c = channels_[channel - 1];
  Status st = record(kMessage, 2 + 4 + 8 + 8 + uint64_t(size));
  if (st) st = u16(channel);
  if (st) st = u32(c.sequence);
  if (st) st = u64(log_ns);
  if (st) st = u64(publish_ns);
  if (st) st = put(data, size);
  if (!st) return st;
  ++c.sequence;
  ++c.messages;
  if (message_count_ == 0 || log_ns < first_ns_) first_ns_ = log_ns;
  if (log_ns > last_ns_) last_ns_ = log_ns;
  ++message_count_;
  return ok();
}

Status McapWriter::close() noexcept {
  if (closed_) return ok();
  closed_ = true;
  // Data end, with the CRC of everything before it (magic and header included).
  const uint32_t data_crc = crc_;
  Status st = record(kDataEnd, 4);
  if (st) st = u32(data_crc);
  // Summary: schemas, channels, statistics (each group's place for the offsets).
  const uint64_t summary_start = bytes_written();
  crc_ = 0;
  uint64_t schema_start = summary_start, channel_start = 0, stats_start = 0, end = 0;
  for (int i = 0; st && i < schema_count_; ++i) st = schema_record(i);
  channel_start = bytes_written();
  for (int i = 0; st && i < channel_count_; ++i) st = channel_record(i);
  stats_start = bytes_written();
  if (st) {
    st = record(kStatistics, 8 + 2 + 4 + 4 + 4 + 4 + 8 + 8 + 4 + uint64_t(channel_count_) * 10);
  }
  if (st) st = u64(message_count_);
  if (st) st = u16(uint16_t(schema_count_));
  if (st) st = u32(uint32_t(channel_count_));
  if (st) st = u32(0);  // attachments
  if (st) st = u32(0);  // metadata
  if (st) st = u32(0);  // chunks
  if (st) st = u64(first_ns_);
  if (st) st = u64(last_ns_);
  if (st) st = u32(uint32_t(channel_count_) * 10);
  for (int i = 0; st && i < channel_count_; ++i) {
    st = u16(uint16_t(i + 1));
    if (st) st = u64(channels_[i].messages);
  }
  end = bytes_written();
  // Summary offsets: one per group present.
  const uint64_t offsets_start = bytes_written();
  const struct {
    uint8_t op;
    uint64_t start, stop;
  } groups[3] = {{kSchema, schema_start, channel_start},
                 {kChannel, channel_start, stats_start},
                 {kStatistics, stats_start, end}};
  for (const auto& g : groups) {
    if (!st || g.stop == g.start) continue;
    st = record(kSummaryOffset, 1 + 8 + 8);
    if (st) st = u8(g.op);
    if (st) st = u64(g.start);
    if (st) st = u64(g.stop - g.start);
  }
  // Footer; its CRC covers the summary sections and the footer up to itself.
  if (st) st = record(kFooter, 8 + 8 + 4);
  if (st) st = u64(summary_start);
  if (st) st = u64(offsets_start);
  if (st) st = u32(crc_);
  if (st) st = put(kMagic, sizeof kMagic);
  if (st) st = flush();
  const int fd = fd_;
  fd_ = -1;
  if (::close(fd) != 0 && st) {
    return Error(Errc::kIo, "mcap: closing the file failed: %s", std::strerror(errno));
  }
  return st;
}

}  // namespace aprt
