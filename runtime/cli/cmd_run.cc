// aprt run [--config FILE] [--model MODEL] [--replay DIR] [--rate HZ] [--threads N] [--quiet]
//
// The service. With no option it runs the embedded default: the shipped
// model on the shipped demo drive (config/default.yaml), printing every pose
// with its error against the ground truth, and exits at the end.
#include <csignal>
#include <cstdio>
#include <cstdlib>
#include <string>

#include "runtime/cli/args.h"
#include "runtime/cli/commands.h"
#include "runtime/config/config.h"
#include "runtime/loop/runtime.h"

namespace aprt::cli {
namespace {

Runtime* g_runtime = nullptr;

void on_signal(int) {
  if (g_runtime) g_runtime->request_stop();
}

// Relative paths in a configuration are relative to `base`.
std::string resolve(const std::string& path, const std::string& base) {
  if (path.empty() || path[0] == '/') return path;
  return base + "/" + path;
}

}  // namespace

int cmd_run(int argc, char** argv) {
  Args args(argc, argv);
  if (args.flag("--help")) {
    std::printf(
        "usage: aprt run [options]\n"
        "  --config FILE   YAML configuration (docs/configuration.md); default:\n"
        "                  the demo drive, %s/config/default.yaml\n"
        "  --model FILE    override the configuration's model\n"
        "  --replay DIR    replay this DeepLoc-layout sequence\n"
        "  --rate HZ       replay rate (0: as fast as inference runs)\n"
        "  --threads N     engine threads\n"
        "  --quiet         no line per pose (summary only)\n",
        data_dir().c_str());
    return 0;
  }
  const char* config_path = args.value("--config");
  const char* model = args.value("--model");
  const char* replay = args.value("--replay");
  const char* rate = args.value("--rate");
  const long threads = args.integer("--threads", 0, 1, 16);
  const bool quiet = args.flag("--quiet");
  if (args.error() || args.leftover()) {
    std::fprintf(stderr, "aprt run: bad argument '%s' (see aprt run --help)\n",
                 args.error() ? args.error() : args.leftover());
    return 2;
  }
  const std::string path = config_path ? config_path : data_dir() + "/config/default.yaml";
  auto loaded = load_config(path);
  if (!loaded) {
    std::fprintf(stderr, "aprt run: %s\n", loaded.error().message());
    return 2;
  }
  Config cfg = loaded.value();
  const std::string base = config_path ? [&] {
    const std::string p(config_path);
    const size_t slash = p.rfind('/');
    return slash == std::string::npos ? std::string(".") : p.substr(0, slash);
  }() : data_dir();
  cfg.model = resolve(model ? model : cfg.model, model ? "." : base);
  if (replay) {
    cfg.source.type = "replay";
    cfg.source.replay.path = replay;
  } else {
    cfg.source.replay.path = resolve(cfg.source.replay.path, base);
  }
  if (rate) {
    char* end = nullptr;
    const double r = std::strtod(rate, &end);
    if (!end || *end || !(r >= 0 && r <= 1000)) {
      std::fprintf(stderr, "aprt run: --rate %s: expected a number in [0, 1000]\n", rate);
      return 2;
    }
    cfg.source.replay.rate_hz = r;
    cfg.source.replay.recorded = false;
  }
  if (threads > 0) cfg.engine.threads = int(threads);
  if (quiet) cfg.output.console = false;
  auto runtime = Runtime::create(cfg);
  if (!runtime) {
    std::fprintf(stderr, "aprt run: %s\n", runtime.error().message());
    return 2;
  }
  g_runtime = runtime->get();
  struct sigaction sa {};
  sa.sa_handler = on_signal;
  sigaction(SIGINT, &sa, nullptr);
  sigaction(SIGTERM, &sa, nullptr);
  const Engine& e = (*runtime)->engine();
  std::printf("aprt run: %s (%s kernels, %d thread%s) on %s\n", cfg.model.c_str(), e.isa(),
              e.threads(), e.threads() > 1 ? "s" : "",
              cfg.source.type == "replay" ? cfg.source.replay.path.c_str()
                                          : cfg.source.v4l2.device.c_str());
  const int code = (*runtime)->run();
  g_runtime = nullptr;
  return code;
}

}  // namespace aprt::cli
