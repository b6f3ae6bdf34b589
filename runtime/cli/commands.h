// The `aprt` subcommands. Each returns a process exit code:
// 0 success, 1 runtime failure, 2 usage error or bad input file.
#pragma once

#include <string>

namespace aprt::cli {

int cmd_info(int argc, char** argv);
int cmd_bench(int argc, char** argv);
int cmd_eval(int argc, char** argv);
int cmd_inputs(int argc, char** argv);
int cmd_run(int argc, char** argv);
int cmd_candump(int argc, char** argv);
int cmd_sign(int argc, char** argv);
int cmd_ddsdump(int argc, char** argv);
int cmd_infer(int argc, char** argv);
int cmd_cameras(int argc, char** argv);

// Where the shipped model, demo drive, DBC and default configuration live:
// $APRT_DATA_DIR, else the build's source tree (or the install prefix).
std::string data_dir();

}  // namespace aprt::cli
