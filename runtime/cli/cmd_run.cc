// aprt run [--config FILE] [--model MODEL] [--replay DIR] [--rate HZ] [--threads N] [--quiet]
//
// The service. With no option it runs the embedded default: the shipped
// model on the shipped demo drive (config/default.yaml), printing every pose
// with its error against the ground truth, and exits at the end.
#include <unistd.h>

#include <csignal>
#include <cstdio>
#include <cstdlib>
#include <string>

#include "runtime/base/allocation_counter.h"
#include "runtime/cli/args.h"
#include "runtime/cli/commands.h"
#include "runtime/config/config.h"
#include "runtime/engine/engine.h"
#include "runtime/loop/model_loader.h"
#include "runtime/loop/process_memory.h"
#include "runtime/loop/runtime.h"

namespace aprt::cli {
namespace {

Runtime* g_runtime = nullptr;

void on_signal(int) {
  if (g_runtime) g_runtime->request_stop();
}

void on_hangup(int) {
  if (g_runtime) g_runtime->request_reload();
}

// Relative paths in a configuration are relative to `base`.
std::string resolve(const std::string& path, const std::string& base) {
  if (path.empty() || path[0] == '/') return path;
  return base + "/" + path;
}

std::string directory_of(const std::string& file) {
  const size_t slash = file.rfind('/');
  return slash == std::string::npos ? std::string(".") : file.substr(0, slash);
}

// --check: what an integrator runs after editing /etc/aprt/aprt.yaml, before
// restarting the service. The configuration has been read and checked; the
// model is loaded for real (checksums, op set, memory plan) with the
// configured engine options.
std::string source_text(const Config::Source& s) {
  if (s.replay_source()) return s.replay.path;
  if (s.type == SourceType::kPointCloud2) return "PointCloud2 on rt" + s.pointcloud2.topic;
  if (s.type == SourceType::kLibcamera) {
    return "libcamera camera " +
           (s.libcamera.camera.empty() ? std::string("0") : s.libcamera.camera);
  }
  return s.v4l2.device;
}

// The memory budget as far as it is known before a thread starts: the
// engine's block (exact), the stacks (threads.stack_kib each), the program and
// its libraries as loaded now, the heap; the run's summary and timing report
// measure the same parts once it runs (docs/configuration.md, "Memory").
void print_budget(const Config& cfg, const Engine& e) {
  const size_t stack = thread_stack_bytes(cfg.threads);
  MemoryBudget now;
  if (!measure_memory(e.memory_block(), e.memory().total_bytes, stack, &now)) return;
  const MemoryReport& m = e.memory();
  auto mb = [](double bytes) { return bytes / 1e6; };
  std::printf(
      "aprt run: memory budget: engine block %.1f MB (tables %.2f, weights kept %.1f, packed "
      "%.1f, arena %.1f, scratch %.1f); thread stacks %zu KiB each (the loop's threads, %d "
      "engine worker%s, the DDS library's); program and libraries %.1f MB resident now; heap "
      "and other %.1f MB; %s\n",
      mb(double(m.total_bytes)), mb(double(m.tables_bytes)), mb(double(m.kept_bytes)),
      mb(double(m.packed_bytes)), mb(double(m.arena_bytes)), mb(double(m.scratch_bytes)),
      stack / 1024, cfg.engine.threads - 1, cfg.engine.threads == 2 ? "" : "s",
      mb(double(now.code_kb) * 1024), mb(double(now.other_kb) * 1024),
      cfg.threads.lock_memory ? "lock_memory: every mapping is locked and resident"
                              : "lock_memory off: only the engine's block is locked");
}

int check_only(const std::string& path, const Config& cfg) {
  std::string note;
  auto engine = load_model(model_request(cfg), &note);
  if (!engine) {
    std::fprintf(stderr, "aprt run: %s: model: %s\n", path.c_str(), engine.error().message());
    return 2;
  }
  if (!note.empty()) std::printf("aprt run: %s: %s\n", cfg.model.c_str(), note.c_str());
  if (Status fit = model_fits_source((*engine)->meta(), cfg.source, cfg.model); !fit) {
    std::fprintf(stderr, "aprt run: %s: %s\n", path.c_str(), fit.error().message());
    return 2;
  }
  std::printf("aprt run: %s: configuration valid; model %s loads (%s kernels, %zu bytes)\n",
              path.c_str(), cfg.model.c_str(), (*engine)->isa(), (*engine)->memory().total_bytes);
  print_budget(cfg, **engine);
  if (!cfg.cameras.empty()) {
    std::printf("aprt run: %zu cameras fused (trigger: %s)\n", cfg.cameras.size(),
                cfg.cameras[0].name.c_str());
  }
  return 0;
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
        "  --replay DIR    replay this DeepLoc-layout sequence (a LiDAR sequence with\n"
        "                  a LiDAR source: lidar_poses.txt + scans), or a recorded\n"
        "                  drive FILE.mcap (--record's, or a ros2 bag in MCAP)\n"
        "  --rate HZ       replay rate (0: as fast as inference runs)\n"
        "  --frames N      stop the replay after N frames\n"
        "  --threads N     engine threads\n"
        "  --quiet         no line per pose (summary only)\n"
        "  --timing FILE   timing validation report: FILE (JSON: per-stage min/median/\n"
        "                  p99/p99.9/max, misses, drops, allocations after the first\n"
        "                  pose, RSS) and FILE with .csv (per-pose timestamps); plot\n"
        "                  with python3 -m aprt_tools plot-timing FILE\n"
        "  --record FILE   record the drive as a ROS 2 bag (MCAP): the frames or\n"
        "                  scans as they entered, every pose, the diagnostics and\n"
        "                  the timing records; replay it with source.type mcap\n"
        "  --record-ring N frames that may wait for the recorder (default 16);\n"
        "                  a full ring drops a frame from the recording, never\n"
        "                  from the drive (counted in the summary)\n"
        "  --save-frame N:FILE  write the raw frame of the N-th pose to FILE and its\n"
        "                  geometry and pose to FILE.txt (check with aprt infer)\n"
        "  --check         validate the configuration and load the model, then exit\n"
        "                  (0: both fine; no device is opened)\n",
        data_dir().c_str());
    return 0;
  }
  const char* config_path = args.value("--config");
  const char* model = args.value("--model");
  const char* replay = args.value("--replay");
  const char* rate = args.value("--rate");
  const long threads = args.integer("--threads", 0, 1, 16);
  const long frames = args.integer("--frames", 0, 1, 1000000000);
  const bool quiet = args.flag("--quiet");
  const bool check = args.flag("--check");
  const char* timing = args.value("--timing");
  const char* save = args.value("--save-frame");
  const char* record = args.value("--record");
  const long record_ring = args.integer("--record-ring", 16, 2, 256);
  if (args.refuse("run")) return 2;
  const std::string path = config_path ? config_path : data_dir() + "/config/default.yaml";
  auto loaded = load_config(path);
  if (!loaded) {
    std::fprintf(stderr, "aprt run: %s\n", loaded.error().message());
    return 2;
  }
  Config cfg = loaded.value();
  const std::string base = config_path ? directory_of(config_path) : data_dir();
  cfg.model = resolve(model ? model : cfg.model, model ? "." : base);
  cfg.model_signing.public_key = resolve(cfg.model_signing.public_key, base);
  cfg.odometry.can.dbc = resolve(cfg.odometry.can.dbc, base);
  // A second sensor (fusion.companion): its own configuration, its paths
  // relative to itself.
  Config companion;
  const bool fused = !cfg.fusion.companion.empty();
  if (fused) {
    const std::string cpath = resolve(cfg.fusion.companion, base);
    auto c = load_config(cpath);
    if (!c) {
      std::fprintf(stderr, "aprt run: %s: fusion.companion: %s\n", path.c_str(),
                   c.error().message());
      return 2;
    }
    companion = c.value();
    if (!companion.fusion.companion.empty() || !companion.cameras.empty()) {
      std::fprintf(stderr,
                   "aprt run: %s: fusion.companion %s: the companion is one sensor: it may "
                   "configure neither `cameras` nor a companion of its own\n",
                   path.c_str(), cpath.c_str());
      return 2;
    }
    const std::string cbase = directory_of(cpath);
    companion.model = resolve(companion.model, cbase);
    companion.model_signing.public_key = resolve(companion.model_signing.public_key, cbase);
    companion.source.replay.path = resolve(companion.source.replay.path, cbase);
  }
  if (replay && !cfg.cameras.empty()) {
    std::fprintf(stderr,
                 "aprt run: --replay replaces the single camera; %s configures %zu cameras\n",
                 path.c_str(), cfg.cameras.size());
    return 2;
  }
  double rate_hz = -1;
  if (rate) {
    char* end = nullptr;
    rate_hz = std::strtod(rate, &end);
    if (!end || *end || !(rate_hz >= 0 && rate_hz <= 1000)) {
      std::fprintf(stderr, "aprt run: --rate %s: expected a number in [0, 1000]\n", rate);
      return 2;
    }
  }
  // The command line's replay options apply to every camera's replay.
  const auto adjust = [&](Config::Source& src) {
    if (replay) {  // a LiDAR configuration replays LiDAR sequences; an .mcap file, itself
      const std::string r(replay);
      const bool mcap = r.size() > 5 && r.compare(r.size() - 5, 5, ".mcap") == 0;
      src.type = mcap                 ? SourceType::kMcap
                 : src.lidar_source() ? SourceType::kLidarReplay
                                      : SourceType::kReplay;
      src.replay.path = replay;
    } else {
      src.replay.path = resolve(src.replay.path, base);
    }
    if (rate_hz >= 0) {
      src.replay.rate_hz = rate_hz;
      src.replay.recorded = false;
    }
    if (frames > 0) src.replay.frames = int(frames);
  };
  adjust(cfg.source);
  for (Config::Camera& cam : cfg.cameras) adjust(cam.source);
  if (fused) {
    // The companion's replay follows the command line too (a drive folder
    // holds both sensors' sequences), its path relative to its own file.
    const std::string kept = companion.source.replay.path;
    adjust(companion.source);
    if (!replay) companion.source.replay.path = kept;
  }
  if (replay && cfg.sanity.filter.enabled && cfg.odometry.source == "replay") {
    // The configuration's filter was chosen for its own drive; a sequence
    // given on the command line without odometry (an MCAP recording, a
    // folder without odometry.txt) runs with the validity gate alone, and
    // says so.
    const std::string r(replay);
    const bool has_odometry =
        cfg.source.type == SourceType::kReplay && access((r + "/odometry.txt").c_str(), F_OK) == 0;
    if (!has_odometry) {
      cfg.sanity.filter.enabled = false;
      std::fprintf(stderr,
                   "aprt run: %s has no odometry (odometry.txt): the pose filter "
                   "(sanity.filter) is off for this run, the validity gate decides\n",
                   replay);
    }
  }
  if (threads > 0) cfg.engine.threads = int(threads);
  if (quiet) cfg.output.console = false;
  if (check) {
    const int code = check_only(path, cfg);
    if (code != 0 || !fused) return code;
    return check_only(companion.origin, companion);
  }
  auto runtime = Runtime::create(cfg, fused ? &companion : nullptr);
  if (!runtime) {
    std::fprintf(stderr, "aprt run: %s\n", runtime.error().message());
    return 2;
  }
  g_runtime = runtime->get();
  struct sigaction sa {};
  sa.sa_handler = on_signal;
  sigaction(SIGINT, &sa, nullptr);
  sigaction(SIGTERM, &sa, nullptr);
  struct sigaction hup {};
  hup.sa_handler = on_hangup;
  sigaction(SIGHUP, &hup, nullptr);
  const Engine& e = (*runtime)->engine();
  std::printf("aprt run: %s (%s kernels, %d thread%s) on %s\n", cfg.model.c_str(), e.isa(),
              e.threads(), e.threads() > 1 ? "s" : "", source_text(cfg.source).c_str());
  for (size_t i = 1; i < cfg.cameras.size(); ++i) {
    const Config::Source& src = cfg.cameras[i].source;
    std::printf("aprt run: fused with camera %s on %s\n", cfg.cameras[i].name.c_str(),
                source_text(src).c_str());
  }
  if (fused) {
    std::printf("aprt run: fused with %s on %s (fusion.companion %s)\n", companion.model.c_str(),
                source_text(companion.source).c_str(), companion.origin.c_str());
  }
  if (save) {
    char* colon = nullptr;
    const long n = std::strtol(save, &colon, 10);
    if (!colon || *colon != ':' || n < 0 || !colon[1]) {
      std::fprintf(stderr, "aprt run: --save-frame %s: expected N:FILE\n", save);
      return 2;
    }
    (*runtime)->save_frame(n, colon + 1);
  }
  if (record) {
    if (Status s = (*runtime)->start_recording(record, int(record_ring)); !s) {
      std::fprintf(stderr, "aprt run: %s\n", s.error().message());
      return 2;
    }
  }
  (*runtime)->set_allocation_counter(allocation_count, allocation_counter_covers_malloc());
  int code = (*runtime)->run();
  g_runtime = nullptr;
  if (record) {
    char line[512];
    const Status s = (*runtime)->finish_recording(line, sizeof line);
    std::printf("%s\n", line);
    if (!s) {
      std::fprintf(stderr, "aprt run: record: %s\n", s.error().message());
      if (code == 0) code = 1;
    }
  }
  if (timing) {
    if (Status s = (*runtime)->write_timing_report(timing); !s) {
      std::fprintf(stderr, "aprt run: %s\n", s.error().message());
      return code ? code : 1;
    }
    std::printf("timing report: %s\n", timing);
  }
  return code;
}

}  // namespace aprt::cli
