#include "drivers/codec/mcap_reader.h"

#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>
#include <new>

namespace aprt {
namespace {

constexpr uint8_t kMagic[8] = {0x89, 'M', 'C', 'A', 'P', '0', '\r', '\n'};
constexpr uint64_t kMaxSmallRecord = 16u << 20;  // schemas, channels: 16 MiB
constexpr uint64_t kMaxMessage = 512ull << 20;   // one frame: 512 MiB

bool read_at(int fd, void* dst, size_t n, uint64_t off) {
  uint8_t* p = static_cast<uint8_t*>(dst);
  while (n > 0) {
    const ssize_t k = pread(fd, p, n, off_t(off));
    if (k < 0 && errno == EINTR) continue;
    if (k <= 0) return false;
    p += k;
    n -= size_t(k);
    off += uint64_t(k);
  }
  return true;
}

// Fields of a record's content, bounds-checked.
struct Cursor {
  const uint8_t* p;
  size_t n, at = 0;
  bool ok = true;
  template <typename T>
  T get() {
    T v{};
    if (at + sizeof v > n) {
      ok = false;
      return v;
    }
    std::memcpy(&v, p + at, sizeof v);
    at += sizeof v;
    return v;
  }
  std::string str() {
    const uint32_t len = get<uint32_t>();
    if (!ok || at + len > n) {
      ok = false;
      return {};
    }
    std::string s(reinterpret_cast<const char*>(p + at), len);
    at += len;
    return s;
  }
};

struct Message {
  uint16_t channel;
  uint64_t offset, log_ns;
  uint32_t size;
};

}  // namespace

McapReader::~McapReader() {
  if (fd_ >= 0) close(fd_);
}

Expected<std::unique_ptr<McapReader>> McapReader::open(const char* path, const std::string& topic,
                                                       const std::vector<std::string>& schemas) {
  std::unique_ptr<McapReader> r(new (std::nothrow) McapReader());
  if (!r) return Error(Errc::kOutOfMemory, "mcap: out of memory");
  r->path_ = path;
  r->fd_ = ::open(path, O_RDONLY | O_CLOEXEC);
  if (r->fd_ < 0) return Error(Errc::kNotFound, "mcap: cannot open %s: %s", path, strerror(errno));
  struct stat st {};
  if (fstat(r->fd_, &st) != 0 || !S_ISREG(st.st_mode)) {
    return Error(Errc::kInvalidArgument, "mcap: %s is not a regular file", path);
  }
  const uint64_t size = uint64_t(st.st_size);
  uint8_t magic[8];
  if (size < 8 || !read_at(r->fd_, magic, 8, 0) || std::memcmp(magic, kMagic, 8) != 0) {
    return Error(Errc::kInvalidArgument, "mcap: %s is not an MCAP file (no MCAP0 magic)", path);
  }
  std::vector<std::pair<uint16_t, std::string>> schema_names;  // id -> name
  std::vector<Message> messages;
  uint64_t off = 8;
  bool data_end = false;
  while (off + 9 <= size) {
    uint8_t head[9];
    if (!read_at(r->fd_, head, 9, off)) return Error(Errc::kIo, "mcap: %s: read failed", path);
    uint64_t len;
    std::memcpy(&len, head + 1, 8);
    const uint8_t op = head[0];
    if (len > size - off - 9) {
      r->truncated_ = true;  // cut inside this record: keep what came before
      break;
    }
    const uint64_t content = off + 9;
    if (op == 0x06 || op == 0x07) {  // Chunk, MessageIndex
      return Error(Errc::kUnsupported,
                   "mcap: %s is chunked (record at byte %llu); aprt replays unchunked files, as "
                   "it records them: convert with `mcap convert` or record without chunking",
                   path, static_cast<unsigned long long>(off));
    }
    if (op == 0x03 || op == 0x04) {  // Schema, Channel
      if (len > kMaxSmallRecord) {
        return Error(Errc::kInvalidArgument, "mcap: %s: a %s record of %llu bytes", path,
                     op == 0x03 ? "schema" : "channel", static_cast<unsigned long long>(len));
      }
      std::vector<uint8_t> b(len);
      if (!read_at(r->fd_, b.data(), len, content)) {
        return Error(Errc::kIo, "mcap: %s: read failed", path);
      }
      Cursor c{b.data(), b.size()};
      if (op == 0x03) {
        const uint16_t id = c.get<uint16_t>();
        std::string name = c.str();
        if (!c.ok) return Error(Errc::kInvalidArgument, "mcap: %s: malformed schema record", path);
        schema_names.emplace_back(id, std::move(name));
      } else {
        McapChannelInfo ch;
        ch.id = c.get<uint16_t>();
        const uint16_t schema = c.get<uint16_t>();
        ch.topic = c.str();
        ch.message_encoding = c.str();
        if (!c.ok) return Error(Errc::kInvalidArgument, "mcap: %s: malformed channel record", path);
        for (const auto& s : schema_names)
          if (s.first == schema) ch.schema_name = s.second;
        bool known = false;
        for (const auto& k : r->channels_) known = known || k.id == ch.id;
        if (!known) r->channels_.push_back(std::move(ch));
      }
    } else if (op == 0x05) {  // Message
      if (len < 22 || len - 22 > kMaxMessage) {
        return Error(Errc::kInvalidArgument, "mcap: %s: a message record of %llu bytes at %llu",
                     path, static_cast<unsigned long long>(len),
                     static_cast<unsigned long long>(off));
      }
      uint8_t m[22];
      if (!read_at(r->fd_, m, 22, content)) return Error(Errc::kIo, "mcap: %s: read failed", path);
      Message msg;
      std::memcpy(&msg.channel, m, 2);
      std::memcpy(&msg.log_ns, m + 6, 8);
      msg.offset = content + 22;
      msg.size = uint32_t(len - 22);
      messages.push_back(msg);
    } else if (op == 0x0F) {  // DataEnd: the summary that follows repeats what we have
      data_end = true;
      break;
    }
    off = content + len;
  }
  if (!data_end && !r->truncated_ && off != size) r->truncated_ = true;
  // The channel to replay.
  const McapChannelInfo* chosen = nullptr;
  for (const auto& ch : r->channels_) {
    if (!topic.empty() ? ch.topic == topic : [&] {
          for (const auto& s : schemas)
            if (ch.schema_name == s) return true;
          return false;
        }()) {
      chosen = &ch;
      break;
    }
  }
  if (!chosen) {
    std::string have;
    for (const auto& ch : r->channels_)
      have += (have.empty() ? "" : ", ") + ch.topic + " (" + ch.schema_name + ")";
    return Error(Errc::kNotFound, "mcap: %s has no %s; its channels: %s", path,
                 topic.empty() ? "image or point cloud channel" : ("channel " + topic).c_str(),
                 have.empty() ? "none" : have.c_str());
  }
  r->channel_ = *chosen;
  if (r->channel_.message_encoding != "cdr") {
    return Error(Errc::kUnsupported, "mcap: %s: channel %s is %s-encoded; aprt reads ROS 2 CDR",
                 path, r->channel_.topic.c_str(), r->channel_.message_encoding.c_str());
  }
  for (const Message& m : messages) {
    if (m.channel != r->channel_.id) continue;
    r->offsets_.push_back(m.offset);
    r->sizes_.push_back(m.size);
    r->log_times_.push_back(m.log_ns);
    if (m.size > r->max_bytes_) r->max_bytes_ = m.size;
  }
  r->channel_.messages = r->offsets_.size();
  if (r->offsets_.empty()) {
    return Error(Errc::kInvalidArgument, "mcap: %s: channel %s has no messages", path,
                 r->channel_.topic.c_str());
  }
  r->buf_.reset(new (std::nothrow) uint8_t[r->max_bytes_]);
  if (!r->buf_) return Error(Errc::kOutOfMemory, "mcap: out of memory");
  return r;
}

Expected<const uint8_t*> McapReader::read(size_t i, size_t* size) {
  if (i >= offsets_.size()) return Error(Errc::kInvalidArgument, "mcap: no message %zu", i);
  if (!read_at(fd_, buf_.get(), sizes_[i], offsets_[i])) {
    return Error(Errc::kIo, "mcap: %s: reading message %zu failed: %s", path_.c_str(), i,
                 strerror(errno));
  }
  *size = sizes_[i];
  return static_cast<const uint8_t*>(buf_.get());
}

}  // namespace aprt
