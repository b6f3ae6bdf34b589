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
#include <fstream>
#include <memory>
#include <sstream>
#include <string>
#include <vector>

#include "kernels/preprocess/preprocess_image.h"
#include "runtime/cli/args.h"
#include "runtime/cli/commands.h"
#include "runtime/cli/open_model.h"
#include "runtime/engine/engine.h"
#include "runtime/engine/engine_input.h"
#include "runtime/engine/pose_decode.h"

namespace aprt::cli {
namespace {

bool parse_format(const std::string& s, PixelFormat* f) {
  for (PixelFormat p : {PixelFormat::kRgb24, PixelFormat::kBgr24, PixelFormat::kYuyv,
                        PixelFormat::kUyvy, PixelFormat::kNv12, PixelFormat::kGray8}) {
    if (s == pixel_format_name(p)) {
      *f = p;
      return true;
    }
  }
  return false;
}

}  // namespace

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
  const double tol = std::atof(tol_text);
  std::ifstream meta(std::string(frame) + ".txt");
  if (!meta) {
    std::fprintf(stderr, "aprt infer: cannot read %s.txt (written beside the frame)\n", frame);
    return 2;
  }
  std::string line, format_name;
  int width = 0, height = 0;
  size_t stride = 0, bytes = 0;
  bool have_pose = false;
  double saved[7] = {};
  while (std::getline(meta, line)) {
    std::istringstream in(line);
    std::string key;
    in >> key;
    if (key == "format") in >> format_name;
    if (key == "width") in >> width;
    if (key == "height") in >> height;
    if (key == "stride") in >> stride;
    if (key == "bytes") in >> bytes;
    if (key == "pose") {
      have_pose = true;
      for (double& v : saved) in >> v;
      have_pose = bool(in);
    }
  }
  PixelFormat format;
  if (!parse_format(format_name, &format) || width <= 0 || height <= 0 || stride == 0) {
    std::fprintf(stderr, "aprt infer: %s.txt: no usable format/width/height/stride\n", frame);
    return 2;
  }
  std::ifstream raw(frame, std::ios::binary);
  std::vector<uint8_t> pixels((std::istreambuf_iterator<char>(raw)),
                              std::istreambuf_iterator<char>());
  if (pixels.size() != bytes || bytes < frame_bytes(format, width, height)) {
    std::fprintf(stderr, "aprt infer: %s has %zu bytes, its .txt says %zu (%dx%d %s)\n", frame,
                 pixels.size(), bytes, width, height, format_name.c_str());
    return 2;
  }
  std::unique_ptr<Engine> engine =
      open_model("infer", model, int(threads), isa, uint32_t(format::Modality::kImage));
  if (!engine) return 2;
  Engine& e = *engine;
  const ModelMeta& m = e.meta();
  auto input = EngineInput::for_images(e, format, width, height);
  if (!input) {
    std::fprintf(stderr, "aprt infer: %s\n", input.error().message());
    return 2;
  }
  const ImageView view{pixels.data(), format, width, height, stride};
  input.value()->write_image(view, e);
  (void)e.run();
  const PoseEstimate p = decode_pose(e.output().f32(), m);
  const double here[7] = {p.position[0],    p.position[1],    p.position[2],   p.orientation[0],
                          p.orientation[1], p.orientation[2], p.orientation[3]};
  std::printf("pose  %.9g %.9g %.9g %.9g %.9g %.9g %.9g (%s kernels)\n", here[0], here[1], here[2],
              here[3], here[4], here[5], here[6], e.isa());
  if (!have_pose) return 0;
  double dp = 0, dq = 0;
  for (int k = 0; k < 3; ++k) dp = std::max(dp, std::fabs(here[k] - saved[k]));
  for (int k = 3; k < 7; ++k) dq = std::max(dq, std::fabs(here[k] - saved[k]));
  std::printf("saved %.9g %.9g %.9g %.9g %.9g %.9g %.9g\n", saved[0], saved[1], saved[2], saved[3],
              saved[4], saved[5], saved[6]);
  std::printf("difference: position %.3g m, quaternion %.3g (tolerance %g)\n", dp, dq, tol);
  return dp <= tol && dq <= tol ? 0 : 1;
}

}  // namespace aprt::cli
