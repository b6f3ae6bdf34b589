// Opening files of outside origin without trusting them (docs/hostile_input.md):
// never blocks (O_NONBLOCK at open: a FIFO or a device at the path cannot
// stall the caller), refuses what is not a regular file unless a device is
// what the caller means, and checks the size against a stated limit with
// fstat() before a byte is read. The messages name the path and the check.
#pragma once

#include <cstddef>
#include <cstdint>
#include <string>

#include "runtime/base/expected.h"

namespace aprt {

// An open regular file (closed by the destructor) and its size.
class InputFile {
 public:
  InputFile() = default;
  InputFile(InputFile&& o) noexcept : fd_(o.fd_), size_(o.size_) { o.fd_ = -1; }
  InputFile& operator=(InputFile&& o) noexcept;
  InputFile(const InputFile&) = delete;
  InputFile& operator=(const InputFile&) = delete;
  ~InputFile();

  int fd() const { return fd_; }
  uint64_t size() const { return size_; }
  // Reads up to n bytes (fewer only at the end of the file); -1 on error (errno).
  long read(void* p, size_t n) const;

 private:
  friend Expected<InputFile> open_input_file(const char* path, uint64_t max_bytes,
                                             const char* what);
  int fd_ = -1;
  uint64_t size_ = 0;
};

// `what` names the file's role in messages ("model", "configuration", "scan").
// Refuses: a path that does not open (with errno's text), a FIFO, a socket,
// a character or block device, a directory, and a file larger than
// max_bytes.
Expected<InputFile> open_input_file(const char* path, uint64_t max_bytes, const char* what);

// The whole file into *out (at most max_bytes; the same checks).
Status read_input_file(const char* path, uint64_t max_bytes, const char* what, std::string* out);

}  // namespace aprt
