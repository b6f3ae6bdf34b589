// candump logs, as the localisation side records aprt's CAN output:
// `candump -L` ("(1700000000.123456) can0 301#0011..", CAN FD "310##1<data>",
// error frames with CAN_ERR_FLAG in an 8-digit id) and candump's default
// output ("  can0  301   [8]  00 11 ..", FD "[64]"). A log is outside input:
// each line is parsed whole (fuzzed: tests/fuzz/candump_log_fuzz.cc), and a
// line that is neither a frame nor blank is an error with its reason, never a
// frame guessed from part of it.
#pragma once

#include <string_view>

#include "drivers/output/can/pose_can_codec.h"
#include "runtime/base/expected.h"

namespace aprt::can {

enum class LogLine { kFrame, kBlank };

// One line (without its newline). kFrame fills *f and *t (seconds; 0 in
// the default format, which carries no time); kBlank for an empty line or
// a '#' comment. Refused: an id that is not 3 (standard) or 8 (extended)
// hex digits or out of range, odd or non-hex data, more than 8 bytes
// classic or a length CAN FD does not have, a [len] the bytes disagree
// with, a malformed time, trailing text.
Expected<LogLine> parse_candump_line(std::string_view line, Frame* f, double* t);

}  // namespace aprt::can
