// aprt infer MODEL FRAME.raw [--isa NAME] [--threads N] [--tolerance T]
//
// One frame saved by `aprt run --save-frame` (raw bytes + FRAME.raw.txt with
// its geometry and the pose the run computed) through a model here: prints
// the pose, and when the sidecar holds one, the difference to it -- exit 1
// beyond the tolerance. The HIL rig uses it to check that the pose computed
// in the VM (Debian's kernel, vivid, reference kernels) is the one this
// machine computes for the same bytes.
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <memory>
#include <string>

#include "drivers/codec/frame_sidecar.h"
#include "runtime/base/file_io.h"
#include "runtime/base/text_lines.h"
#include "runtime/cli/args.h"
#include "runtime/cli/commands.h"
#include "runtime/cli/open_model.h"
#include "runtime/engine/engine.h"
#include "runtime/engine/engine_input.h"
#include "runtime/engine/pose_decode.h"

namespace aprt::cli {

int cmd_infer(int argc, char** argv) {
  Args args(argc, argv);
  if (args.flag("--help")) {
    std::printf(
        "usage: aprt infer MODEL FRAME.raw [--isa NAME] [--threads N] [--tolerance T]\n"
        "  FRAME.raw and FRAME.raw.txt as written by aprt run --save-frame N:FRAME.raw\n"
        "  --tolerance T  largest accepted difference to the saved pose (metres, and\n"
        "                 quaternion components), default 1e-3\n");
    return 0;
  }
  const char* isa = args.value("--isa");
  const long threads = args.integer("--threads", 1, 1, 16);
  const char* tol_text = args.value("--tolerance", "1e-3");
  const char* model = args.positional();
  const char* frame = args.positional();
  if (args.refuse("infer")) return 2;
  if (!model || !frame) {
    std::fprintf(stderr, "aprt infer: usage: aprt infer MODEL FRAME.raw (see --help)\n");
    return 2;
  }
  double tol = 0;
  if (!parse_finite(tol_text, &tol) || tol < 0) {
    std::fprintf(stderr, "aprt infer: --tolerance: expected a number >= 0, got '%s'\n", tol_text);
    return 2;
  }
  const std::string sidecar_path = std::string(frame) + ".txt";
  std::string text;
  if (Status s = read_input_file(sidecar_path.c_str(), 1 << 16, "frame sidecar", &text); !s) {
    std::fprintf(stderr, "aprt infer: %s (written beside the frame by aprt run --save-frame)\n",
                 s.error().message());
    return 2;
  }
  auto side = parse_frame_sidecar(text, sidecar_path.c_str());
  if (!side) {
    std::fprintf(stderr, "aprt infer: %s\n", side.error().message());
    return 2;
  }
  const FrameSidecar& sc = side.value();
  std::string pixels;
  if (Status s = read_input_file(frame, sc.bytes, "frame", &pixels); !s) {
    std::fprintf(stderr, "aprt infer: %s\n", s.error().message());
    return 2;
  }
  if (pixels.size() != sc.bytes) {
    std::fprintf(stderr, "aprt infer: %s has %zu bytes, %s says %zu\n", frame, pixels.size(),
                 sidecar_path.c_str(), sc.bytes);
    return 2;
  }
  std::unique_ptr<Engine> engine =
      open_model("infer", model, int(threads), isa, uint32_t(format::Modality::kImage));
  if (!engine) return 2;
  Engine& e = *engine;
  const ModelMeta& m = e.meta();
  auto input = EngineInput::for_images(e, sc.format, sc.width, sc.height);
  if (!input) {
    std::fprintf(stderr, "aprt infer: %s\n", input.error().message());
    return 2;
  }
  const ImageView view{reinterpret_cast<const uint8_t*>(pixels.data()), sc.format, sc.width,
                       sc.height, sc.stride};
  input.value()->write_image(view, e);
  (void)e.run();
  const PoseEstimate p = decode_pose(e.output().f32(), m);
  const double here[7] = {p.position[0],    p.position[1],    p.position[2],   p.orientation[0],
                          p.orientation[1], p.orientation[2], p.orientation[3]};
  std::printf("pose  %.9g %.9g %.9g %.9g %.9g %.9g %.9g (%s kernels)\n", here[0], here[1], here[2],
              here[3], here[4], here[5], here[6], e.isa());
  if (!sc.have_pose) return 0;
  const double* saved = sc.pose;
  double dp = 0, dq = 0;
  for (int k = 0; k < 3; ++k) dp = std::max(dp, std::fabs(here[k] - saved[k]));
  for (int k = 3; k < 7; ++k) dq = std::max(dq, std::fabs(here[k] - saved[k]));
  std::printf("saved %.9g %.9g %.9g %.9g %.9g %.9g %.9g\n", saved[0], saved[1], saved[2], saved[3],
              saved[4], saved[5], saved[6]);
  std::printf("difference: position %.3g m, quaternion %.3g (tolerance %g)\n", dp, dq, tol);
  return dp <= tol && dq <= tol ? 0 : 1;
}

}  // namespace aprt::cli
