// aprt: the runtime's one binary.
#include <unistd.h>

#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <string>

#include "kernels/table/cpu_features.h"
#include "runtime/cli/commands.h"

namespace {

void usage(FILE* out) {
  std::fprintf(out,
               "usage: aprt <command> [options]\n"
               "\n"
               "commands:\n"
               "  run            the service; with no options, the demo drive\n"
               "  info MODEL     what a model file holds: metadata, ops, memory plan\n"
               "  bench MODEL    latency and memory of a model on this machine\n"
               "  eval           errors of a model on a labelled sequence\n"
               "  inputs         the network inputs of a labelled sequence, as a .npy array\n"
               "  infer MODEL F  one saved raw frame (aprt run --save-frame) through a model\n"
               "  candump        decode aprt's pose frames from CAN (the receiver's view)\n"
               "  ddsdump        receive aprt's poses and status over DDS (the ROS 2 side's view)\n"
               "  sign           Ed25519 keys and model signatures (model_signing)\n"
               "  cameras        the V4L2 and libcamera cameras this machine offers\n"
               "\n"
               "Run 'aprt <command> --help' for the command's options.\n");
}

}  // namespace

#ifndef APRT_DATA_DIR
#define APRT_DATA_DIR "."
#endif

// The shipped configuration, model and demo drive: $APRT_DATA_DIR if set;
// else <prefix>/share/aprt beside an installed binary (<prefix>/bin/aprt),
// wherever the package was unpacked; else the source tree of this build.
std::string aprt::cli::data_dir() {
  const char* env = std::getenv("APRT_DATA_DIR");
  if (env && *env) return env;
  char exe[4096];
  const ssize_t n = readlink("/proc/self/exe", exe, sizeof exe - 1);
  if (n > 0) {
    std::string dir(exe, size_t(n));
    dir = dir.substr(0, dir.rfind('/'));                  // <prefix>/bin
    dir = dir.substr(0, dir.rfind('/')) + "/share/aprt";  // <prefix>/share/aprt
    if (access((dir + "/config/default.yaml").c_str(), R_OK) == 0) return dir;
  }
  return APRT_DATA_DIR;
}

int main(int argc, char** argv) {
  // Before anything else runs code the compiler may have vectorised for the build's -march.
  if (const char* missing = aprt::kernels::missing_build_feature()) {
    std::fprintf(stderr,
                 "aprt: this binary was built for a CPU with %s; this CPU does not report it. "
                 "Install the build for this target's baseline (see README, On the ECU).\n",
                 missing);
    return 70;
  }
  if (argc < 2 || !std::strcmp(argv[1], "--help") || !std::strcmp(argv[1], "-h")) {
    usage(argc < 2 ? stderr : stdout);
    return argc < 2 ? 2 : 0;
  }
  const char* cmd = argv[1];
  if (!std::strcmp(cmd, "run")) return aprt::cli::cmd_run(argc - 1, argv + 1);
  if (!std::strcmp(cmd, "info")) return aprt::cli::cmd_info(argc - 1, argv + 1);
  if (!std::strcmp(cmd, "bench")) return aprt::cli::cmd_bench(argc - 1, argv + 1);
  if (!std::strcmp(cmd, "eval")) return aprt::cli::cmd_eval(argc - 1, argv + 1);
  if (!std::strcmp(cmd, "inputs")) return aprt::cli::cmd_inputs(argc - 1, argv + 1);
  if (!std::strcmp(cmd, "candump")) return aprt::cli::cmd_candump(argc - 1, argv + 1);
  if (!std::strcmp(cmd, "sign")) return aprt::cli::cmd_sign(argc - 1, argv + 1);
  if (!std::strcmp(cmd, "ddsdump")) return aprt::cli::cmd_ddsdump(argc - 1, argv + 1);
  if (!std::strcmp(cmd, "infer")) return aprt::cli::cmd_infer(argc - 1, argv + 1);
  if (!std::strcmp(cmd, "cameras")) return aprt::cli::cmd_cameras(argc - 1, argv + 1);
  std::fprintf(stderr, "aprt: unknown command '%s'\n", cmd);
  usage(stderr);
  return 2;
}
