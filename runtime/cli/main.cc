// aprt: the runtime's one binary.
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <string>

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
               "  candump        decode aprt's pose frames from CAN (the receiver's view)\n"
               "\n"
               "Run 'aprt <command> --help' for the command's options.\n");
}

}  // namespace

#ifndef APRT_DATA_DIR
#define APRT_DATA_DIR "."
#endif

std::string aprt::cli::data_dir() {
  const char* env = std::getenv("APRT_DATA_DIR");
  return env && *env ? env : APRT_DATA_DIR;
}

int main(int argc, char** argv) {
  if (argc < 2 || !std::strcmp(argv[1], "--help") || !std::strcmp(argv[1], "-h")) {
    usage(argc < 2 ? stderr : stdout);
    return argc < 2 ? 2 : 0;
  }
  const char* cmd = argv[1];
  if (!std::strcmp(cmd, "run")) return aprt::cli::cmd_run(argc - 1, argv + 1);
  if (!std::strcmp(cmd, "info")) return aprt::cli::cmd_info(argc - 1, argv + 1);
  if (!std::strcmp(cmd, "bench")) return aprt::cli::cmd_bench(argc - 1, argv + 1);
  if (!std::strcmp(cmd, "eval")) return aprt::cli::cmd_eval(argc - 1, argv + 1);
  if (!std::strcmp(cmd, "candump")) return aprt::cli::cmd_candump(argc - 1, argv + 1);
  std::fprintf(stderr, "aprt: unknown command '%s'\n", cmd);
  usage(stderr);
  return 2;
}
