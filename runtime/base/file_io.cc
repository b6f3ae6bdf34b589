#include "runtime/base/file_io.h"

#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>

namespace aprt {
namespace {

const char* kind_of(mode_t m) {
  if (S_ISFIFO(m)) return "a FIFO";
  if (S_ISSOCK(m)) return "a socket";
  if (S_ISCHR(m)) return "a character device";
  if (S_ISBLK(m)) return "a block device";
  if (S_ISDIR(m)) return "a directory";
  return "not a regular file";
}

}  // namespace

InputFile& InputFile::operator=(InputFile&& o) noexcept {
  if (this != &o) {
    if (fd_ >= 0) close(fd_);
    fd_ = o.fd_;
    size_ = o.size_;
    o.fd_ = -1;
  }
  return *this;
}

InputFile::~InputFile() {
  if (fd_ >= 0) close(fd_);
}

long InputFile::read(void* p, size_t n) const {
  size_t got = 0;
  while (got < n) {
    const ssize_t r = ::read(fd_, static_cast<char*>(p) + got, n - got);
    if (r < 0 && errno == EINTR) continue;
    if (r < 0) return -1;
    if (r == 0) break;
    got += size_t(r);
  }
  return long(got);
}

Expected<InputFile> open_input_file(const char* path, uint64_t max_bytes, const char* what) {
  InputFile f;
  // O_NONBLOCK: opening a FIFO for reading would otherwise wait for a writer.
  f.fd_ = open(path, O_RDONLY | O_CLOEXEC | O_NONBLOCK | O_NOCTTY);
  if (f.fd_ < 0) {
    return Error(Errc::kIo, "%s: cannot open %s: %s", what, path, std::strerror(errno));
  }
  struct stat st {};
  if (fstat(f.fd_, &st) != 0) {
    return Error(Errc::kIo, "%s: %s: %s", what, path, std::strerror(errno));
  }
  if (!S_ISREG(st.st_mode)) {
    return Error(Errc::kInvalidArgument, "%s: %s is %s, not a file", what, path,
                 kind_of(st.st_mode));
  }
  if (uint64_t(st.st_size) > max_bytes) {
    return Error(Errc::kInvalidArgument, "%s: %s is %llu bytes, more than the %llu a %s may have",
                 what, path, static_cast<unsigned long long>(st.st_size),
                 static_cast<unsigned long long>(max_bytes), what);
  }
  // A regular file never blocks; clear the flag so reads behave plainly.
  const int flags = fcntl(f.fd_, F_GETFL);
  if (flags >= 0) fcntl(f.fd_, F_SETFL, flags & ~O_NONBLOCK);
  f.size_ = uint64_t(st.st_size);
  return f;
}

Status read_input_file(const char* path, uint64_t max_bytes, const char* what, std::string* out) {
  auto f = open_input_file(path, max_bytes, what);
  if (!f) return f.error();
  out->resize(size_t(f->size()));
  const long n = f->read(out->data(), out->size());
  if (n < 0) return Error(Errc::kIo, "%s: %s: %s", what, path, std::strerror(errno));
  if (uint64_t(n) != f->size()) {
    return Error(Errc::kTruncated, "%s: %s changed while it was read (%ld of %llu bytes)", what,
                 path, n, static_cast<unsigned long long>(f->size()));
  }
  return ok();
}

}  // namespace aprt
