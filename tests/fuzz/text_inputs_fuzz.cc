// libFuzzer targets for the line-oriented files aprt reads: one binary per
// parser, chosen at build time (APRT_FUZZ_PARSER):
//   1 poses.txt and times.txt (a replay's pose list and its recorded times)
//   2 FRAME.raw.txt (a saved frame's sidecar, read by aprt infer)
//   3 a candump log, line by line (aprt candump --log)
// Each must refuse with a reason or accept; what it accepts must hold what
// the parser promises (finite numbers, normalised quaternions, increasing
// times, a frame the stated bytes hold, a CAN frame's length).
#include <cmath>
#include <cstdint>
#include <cstdlib>
#include <string_view>
#include <vector>

#include "drivers/codec/frame_sidecar.h"
#include "drivers/input/replay/pose_list.h"
#include "drivers/output/can/candump_log.h"

namespace {

[[maybe_unused]] void pose_lists(std::string_view text) {
  // The first line break splits the input into a pose list and its times.
  const size_t split = text.find('\f');
  std::vector<aprt::ReplayEntry> e;
  if (!aprt::parse_pose_list(text.substr(0, split), "poses.txt", &e)) return;
  for (const auto& r : e) {
    double n = 0;
    for (double q : r.orientation) n += q * q;
    if (std::fabs(n - 1.0) > 1e-6 || !std::isfinite(r.position[0])) std::abort();
  }
  if (split == std::string_view::npos) return;
  if (!aprt::parse_times(text.substr(split + 1), "times.txt", &e)) return;
  for (size_t i = 1; i < e.size(); ++i) {
    if (!(e[i].time_s > e[i - 1].time_s)) std::abort();
  }
}

[[maybe_unused]] void sidecar(std::string_view text) {
  auto s = aprt::parse_frame_sidecar(text, "frame.raw.txt");
  if (!s) return;
  if (s->bytes < aprt::image_span(s->format, s->width, s->height, s->stride)) std::abort();
  if (s->stride < aprt::min_stride(s->format, s->width)) std::abort();
}

[[maybe_unused]] void candump(std::string_view text) {
  size_t pos = 0;
  while (pos < text.size()) {
    const size_t nl = text.find('\n', pos);
    const std::string_view line = text.substr(pos, nl == std::string_view::npos ? nl : nl - pos);
    pos = nl == std::string_view::npos ? text.size() : nl + 1;
    aprt::can::Frame f;
    double t = 0;
    auto r = aprt::can::parse_candump_line(line, &f, &t);
    if (!r || r.value() != aprt::can::LogLine::kFrame) continue;
    if (f.len > (f.fd ? 64 : 8) || !std::isfinite(t)) std::abort();
  }
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  const std::string_view text(reinterpret_cast<const char*>(data), size);
#if APRT_FUZZ_PARSER == 1
  pose_lists(text);
#elif APRT_FUZZ_PARSER == 2
  sidecar(text);
#else
  candump(text);
#endif
  return 0;
}
