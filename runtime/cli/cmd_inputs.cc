// aprt inputs --model MODEL --data DIR --out FILE.npy [--every N] [--limit N] [--isa X]
//
// Writes the network inputs the runtime computes for the frames of a
// labelled sequence -- camera frames preprocessed as `aprt run` does, LiDAR
// scans through the point gate into the model's BEV histogram or sampled
// points -- as one NumPy array [frames, H, W, C] float32 (NHWC, the engine's
// input layout), in sequence order (every N-th frame). Uses: a calibration set
// for `aprt_tools quantize`, and `aprt_tools train --inputs` (LiDAR points
// models: the C++ farthest-point sampler is ~15x faster than the Python one).
// Frames that cannot be read are refused (the array would lose its order).
#include <cerrno>
#include <cstdio>
#include <cstring>
#include <memory>
#include <string>

#include "runtime/cli/args.h"
#include "runtime/cli/commands.h"
#include "runtime/cli/eval_inputs.h"
#include "runtime/cli/open_model.h"
#include "runtime/engine/engine.h"

namespace aprt::cli {
namespace {

// NPY format 1.0: magic, version, header length, a Python dict literal padded
// with spaces to a multiple of 64 bytes and ended by a newline.
bool write_npy_header(FILE* f, size_t frames, const uint32_t* shape) {
  char dict[256];
  const int n = std::snprintf(
      dict, sizeof dict, "{'descr': '<f4', 'fortran_order': False, 'shape': (%zu, %u, %u, %u), }",
      frames, shape[1], shape[2], shape[3]);
  if (n <= 0 || size_t(n) >= sizeof dict) return false;
  size_t total = 10 + size_t(n) + 1;
  const size_t padded = (total + 63) / 64 * 64;
  std::string h(dict, size_t(n));
  h.append(padded - total, ' ');
  h.push_back('\n');
  const uint16_t len = uint16_t(h.size());
  const unsigned char magic[8] = {0x93, 'N', 'U', 'M', 'P', 'Y', 1, 0};
  return std::fwrite(magic, 1, 8, f) == 8 && std::fwrite(&len, 2, 1, f) == 1 &&
         std::fwrite(h.data(), 1, h.size(), f) == h.size();
}

}  // namespace

int cmd_inputs(int argc, char** argv) {
  Args args(argc, argv);
  if (args.flag("--help")) {
    std::printf(
        "usage: aprt inputs --model MODEL --data DIR --out FILE.npy [--every N] [--limit N]\n"
        "                   [--isa X]\n"
        "  the network inputs the runtime computes for a labelled sequence (camera frames,\n"
        "  or LiDAR scans for a BEV / points model), as a NumPy array [frames, H, W, C]\n"
        "  float32: a calibration set for `aprt_tools quantize`, training inputs for\n"
        "  `aprt_tools train --inputs`\n");
    return 0;
  }
  const char* model_path = args.value("--model");
  const char* data = args.value("--data");
  const char* out = args.value("--out");
  const long every = args.integer("--every", 1, 1, 1000000);
  const long limit = args.integer("--limit", 0, 0, 100000000);
  const char* isa = args.value("--isa");
  if (args.refuse("inputs")) return 2;
  if (!model_path || !data || !out) {
    std::fprintf(stderr, "aprt inputs: --model, --data and --out are required (see --help)\n");
    return 2;
  }
  std::unique_ptr<Engine> engine = open_model("inputs", model_path, 1, isa);
  if (!engine) return 2;
  Engine& e = *engine;
  std::unique_ptr<EvalInputs> inputs = open_eval_inputs(data, e);
  if (!inputs) return 2;
  size_t frames = (inputs->size() + size_t(every) - 1) / size_t(every);
  if (limit > 0 && size_t(limit) < frames) frames = size_t(limit);
  FILE* f = std::fopen(out, "wb");
  if (!f) {
    std::fprintf(stderr, "aprt inputs: cannot write %s: %s\n", out, std::strerror(errno));
    return 1;
  }
  bool ok = write_npy_header(f, frames, e.meta().input_shape);
  const size_t floats = e.input().numel;
  for (size_t k = 0; ok && k < frames; ++k) {
    EvalFrame frame;
    const char* why = nullptr;
    if (!inputs->fill(k * size_t(every), e, &frame, &why)) {
      std::fprintf(stderr, "aprt inputs: frame %zu: %s\n", k * size_t(every), why ? why : "?");
      std::fclose(f);
      std::remove(out);
      return 2;
    }
    ok = std::fwrite(e.input().f32(), sizeof(float), floats, f) == floats;
  }
  ok = std::fclose(f) == 0 && ok;
  if (!ok) {
    std::fprintf(stderr, "aprt inputs: writing %s failed\n", out);
    std::remove(out);
    return 1;
  }
  std::printf("aprt inputs: %s: %zu frames of %ux%ux%u from %s (every %ld)\n", out, frames,
              e.meta().input_shape[1], e.meta().input_shape[2], e.meta().input_shape[3], data,
              every);
  return 0;
}

}  // namespace aprt::cli
