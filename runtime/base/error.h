// Errors as values: a code for programs, a message for people.
//
// An Error owns a fixed-size message buffer, so making one never allocates;
// it may be created on the real-time path. Messages say what failed and, where
// it helps, what to do ("model_bin: section WEIGHTS checksum mismatch (file
// truncated?)").
#pragma once

#include <cstdarg>
#include <cstddef>
#include <cstdint>

namespace aprt {

enum class Errc : uint16_t {
  kOk = 0,
  kIo,                  // open/read/stat failed
  kTruncated,           // file shorter than its header or a table says
  kBadMagic,            // not a model_bin file
  kUnsupportedVersion,  // major version this build cannot read
  kBadHeader,           // header fields inconsistent
  kChecksum,            // CRC mismatch
  kSectionBounds,       // section outside the file, overlapping, duplicated or missing
  kMisaligned,          // offset not 64-byte aligned
  kBadMetadata,         // META missing/invalid field
  kBadTensor,           // tensor table entry invalid
  kBadOp,               // op record invalid (opcode, indices, params)
  kShapeMismatch,       // shapes inconsistent with an op
  kBadGraph,            // use before definition, double definition, ...
  kTooLarge,            // absurd sizes
  kOutOfMemory,
  kWrongTarget,  // valid file, but not for this runtime/configuration
  kInvalidArgument,
  kUnsupported,
  kNotReady,
  kNotFound,  // a device or interface that does not exist (yet)
  // Kernels for an ISA this CPU lacks or this build does not contain (--isa,
  // APRT_ISA): the one refusal a test may skip on (every other is a failure).
  kIsaUnavailable,
};

const char* errc_name(Errc code) noexcept;

class Error {
 public:
  static constexpr size_t kCapacity = 256;

  Error() noexcept : code_(Errc::kOk) { message_[0] = '\0'; }
  Error(Errc code, const char* format, ...) noexcept __attribute__((format(printf, 3, 4)));

  Errc code() const noexcept { return code_; }
  const char* message() const noexcept { return message_; }

  // Prepends "context: " to the message (truncating at capacity).
  Error& with_context(const char* format, ...) noexcept __attribute__((format(printf, 2, 3)));

 private:
  Errc code_;
  char message_[kCapacity];
};

}  // namespace aprt
