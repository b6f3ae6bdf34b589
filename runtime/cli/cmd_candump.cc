// aprt candump (--interface IF | --log FILE) [--dbc FILE] [--config FILE] ...
//
// The localisation ECU's view of aprt's CAN output: frames from a SocketCAN
// interface or a candump log, checked like a receiver checks them (E2E CRC,
// alive counter continuity, the five classic frames of one estimate
// together) and decoded with the DBC file into poses.
#include <cerrno>
#include <cinttypes>
#include <cmath>
#include <csignal>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <ctime>
#include <string>

#include "drivers/can/dbc.h"
#include "drivers/can/socketcan.h"
#include "drivers/output/can/candump_log.h"
#include "drivers/output/can/pose_can_codec.h"
#include "runtime/base/angles.h"
#include "runtime/base/file_io.h"
#include "runtime/cli/args.h"
#include "runtime/cli/commands.h"
#include "runtime/config/config.h"

namespace aprt::cli {
namespace {

volatile std::sig_atomic_t g_stop = 0;
void on_signal(int) {
  g_stop = 1;
}

struct Printer {
  const can::Dbc* dbc;
  can::Ids ids;
  bool quiet = false, raw = false;
  can::Frame last[6];
  uint64_t disagreements = 0;

  const can::DbcMessage* msg(uint32_t id) const { return dbc->message(id); }

  double sig(uint32_t id, const char* name, const can::Frame& f) const {
    const can::DbcMessage* m = msg(id);
    const can::DbcSignal* s = m ? m->signal(name) : nullptr;
    return s ? s->physical(f.data, f.len) : NAN;
  }

  void frame(const can::Frame& f, double t) {
    if (!raw) return;
    const can::DbcMessage* m = msg(f.id);
    std::printf("%.6f  %03X %-14s", t, unsigned(f.id), m ? m->name.c_str() : "(not in DBC)");
    if (m) {
      for (const auto& s : m->signals)
        std::printf(" %s=%g", s.name.c_str(), s.physical(f.data, f.len));
    }
    std::printf("\n");
  }

  // Prints an estimate decoded with the DBC from the frames just fed.
  void estimate(const can::PoseSignals& codec, bool fd, double t) {
    const can::Frame& st = fd ? last[5] : last[0];
    const uint32_t st_id = fd ? ids.fd : ids.status;
    can::PoseSignals s;
    s.state = uint8_t(sig(st_id, "State", st));
    s.flags = uint16_t(sig(st_id, "Flags", st));
    s.valid = sig(st_id, "Valid", st) != 0;
    s.sigma_pos_m = sig(st_id, "SigmaPos", st);
    s.sigma_yaw_deg = sig(st_id, "SigmaYaw", st);
    if (fd) {
      s.x = sig(ids.fd, "PosX", st);
      s.y = sig(ids.fd, "PosY", st);
      s.z = sig(ids.fd, "PosZ", st);
      s.qw = sig(ids.fd, "QuatW", st);
      s.qx = sig(ids.fd, "QuatX", st);
      s.qy = sig(ids.fd, "QuatY", st);
      s.qz = sig(ids.fd, "QuatZ", st);
      s.timestamp_us = uint64_t(sig(ids.fd, "TimestampUs", st));
    } else {
      s.x = sig(ids.pos_xy, "PosX", last[1]);
      s.y = sig(ids.pos_xy, "PosY", last[1]);
      s.z = sig(ids.pos_zqw, "PosZ", last[2]);
      s.qw = sig(ids.pos_zqw, "QuatW", last[2]);
      s.qx = sig(ids.pos_zqw, "QuatX", last[2]);
      s.qy = sig(ids.quat_yz, "QuatY", last[3]);
      s.qz = sig(ids.quat_yz, "QuatZ", last[3]);
      s.timestamp_us = uint64_t(sig(ids.time, "TimestampUs", last[4]));
    }
    const double tol = 1e-6;
    if (std::fabs(s.x - codec.x) > tol || std::fabs(s.y - codec.y) > tol ||
        std::fabs(s.qw - codec.qw) > tol || s.flags != codec.flags || s.valid != codec.valid) {
      ++disagreements;
      std::printf("warning: the DBC and aprt's codec decode this estimate differently\n");
    }
    if (quiet) return;
    const double yaw = yaw_of_quaternion(s.qw, s.qx, s.qy, s.qz);
    const can::DbcMessage* sm = msg(st_id);
    const can::DbcSignal* state_sig = sm ? sm->signal("State") : nullptr;
    const char* state_name = "?";
    if (state_sig) {
      auto it = state_sig->values.find(s.state);
      if (it != state_sig->values.end()) state_name = it->second.c_str();
    }
    const time_t secs = time_t(s.timestamp_us / 1000000);
    tm utc{};
    gmtime_r(&secs, &utc);
    char when[32];
    std::strftime(when, sizeof when, "%H:%M:%S", &utc);
    std::printf(
        "%.6f  ctr %2u %-8s %s  x %10.2f y %10.2f z %7.2f  yaw %7.2f deg  sigma %.2f m %.1f deg  "
        "stamp %s.%06u  flags 0x%04x\n",
        t, unsigned(st.data[1] & 0x0F), state_name, s.valid ? "VALID  " : "invalid", s.x, s.y, s.z,
        yaw * 180.0 / M_PI, s.sigma_pos_m, s.sigma_yaw_deg, when,
        unsigned(s.timestamp_us % 1000000), unsigned(s.flags));
  }
};

}  // namespace

int cmd_candump(int argc, char** argv) {
  Args args(argc, argv);
  if (args.flag("--help")) {
    std::printf(
        "usage: aprt candump (--interface IF | --log FILE) [options]\n"
        "  --interface IF  read a SocketCAN interface (classic and FD frames)\n"
        "  --log FILE      read a candump log (candump -L, or candump's default output)\n"
        "  --dbc FILE      the DBC to decode with (default %s/config/aprt_pose.dbc)\n"
        "  --config FILE   take the CAN ids from this aprt configuration (output.can.ids)\n"
        "  --count N       stop after N estimates\n"
        "  --timeout S     stop after S seconds without a frame (interface; default: never)\n"
        "  --raw           print every frame's signals too\n"
        "  --quiet         the summary only\n"
        "  --strict        exit 1 if any CRC, counter or grouping error was seen, a\n"
        "                  log line was no frame, or no frame came at all\n"
        "  --tolerate-loss with --strict: lost frames (a skipped counter, an incomplete\n"
        "                  estimate) are what E2E detects on a bus outage, not a fault;\n"
        "                  only CRC errors, repeated counters and DBC disagreements fail\n",
        data_dir().c_str());
    return 0;
  }
  const char* interface = args.value("--interface");
  const char* log = args.value("--log");
  const std::string dbc_path = args.value("--dbc", (data_dir() + "/config/aprt_pose.dbc").c_str());
  const char* config_path = args.value("--config");
  const long count = args.integer("--count", 0, 0, 1L << 40);
  const long timeout_s = args.integer("--timeout", 0, 0, 1L << 20);
  const bool raw = args.flag("--raw"), quiet = args.flag("--quiet"), strict = args.flag("--strict"),
             tolerate_loss = args.flag("--tolerate-loss");
  if (args.refuse("candump")) return 2;
  if (!interface == !log) {
    std::fprintf(stderr, "aprt candump: give exactly one of --interface and --log (see --help)\n");
    return 2;
  }
  auto dbc = can::load_dbc(dbc_path);
  if (!dbc) {
    std::fprintf(stderr, "aprt candump: %s\n", dbc.error().message());
    return 2;
  }
  can::Ids ids;
  if (config_path) {
    auto cfg = load_config(config_path);
    if (!cfg) {
      std::fprintf(stderr, "aprt candump: %s\n", cfg.error().message());
      return 2;
    }
    const int* c = cfg->output.can.ids;
    ids = {uint32_t(c[0]), uint32_t(c[1]), uint32_t(c[2]),
           uint32_t(c[3]), uint32_t(c[4]), uint32_t(c[5])};
  } else {
    // The ids the DBC gives its messages.
    const char* names[6] = {"APRT_Status", "APRT_PosXY", "APRT_PosZQw",
                            "APRT_QuatYZ", "APRT_Time",  "APRT_PoseFD"};
    uint32_t* slots[6] = {&ids.status, &ids.pos_xy, &ids.pos_zqw, &ids.quat_yz, &ids.time, &ids.fd};
    for (int i = 0; i < 6; ++i) {
      const can::DbcMessage* m = dbc->message(std::string(names[i]));
      if (!m) {
        std::fprintf(stderr, "aprt candump: %s: message %s not defined\n", dbc_path.c_str(),
                     names[i]);
        return 2;
      }
      *slots[i] = m->id;
    }
  }
  can::Decoder decoder(ids);
  Printer printer{&dbc.value(), ids, quiet, raw, {}, 0};
  const uint32_t all_ids[6] = {ids.status, ids.pos_xy, ids.pos_zqw, ids.quat_yz, ids.time, ids.fd};
  uint64_t frames = 0, error_frames = 0, other = 0;
  auto feed = [&](const can::Frame& f, double t) {
    ++frames;
    if (f.id & can::SocketCan::kErrorFrameFlag) {
      ++error_frames;
      if (!quiet) std::printf("%.6f  error frame 0x%08X\n", t, unsigned(f.id & 0x1FFFFFFF));
      return;
    }
    printer.frame(f, t);
    for (int i = 0; i < 6; ++i) {
      if (all_ids[i] == f.id) printer.last[i] = f;
    }
    can::PoseSignals s;
    const can::Decoder::Event e = decoder.feed(f, &s);
    if (e == can::Decoder::Event::kEstimate) {
      printer.estimate(s, f.id == ids.fd, t);
    } else if (e == can::Decoder::Event::kUnknownId) {
      ++other;
    } else if (e != can::Decoder::Event::kNone && !quiet) {
      std::printf("%.6f  %03X %s\n", t, unsigned(f.id), can::event_name(e));
    }
  };
  uint64_t malformed = 0;
  if (log) {
    // Streamed in blocks: a log of hours is hundreds of MB. Bounded I/O (a
    // FIFO or a device at the path is refused), every line parsed whole.
    auto in = open_input_file(log, uint64_t(1) << 40, "candump log");
    if (!in) {
      std::fprintf(stderr, "aprt candump: %s\n", in.error().message());
      return 2;
    }
    std::string pending;
    char block[1 << 16];
    uint64_t lineno = 0;
    bool done = false;
    auto line = [&](std::string_view text) {
      ++lineno;
      can::Frame f;
      double t = 0;
      auto r = can::parse_candump_line(text, &f, &t);
      if (!r) {
        if (++malformed <= 5)
          std::fprintf(stderr, "%s:%llu: %s\n", log, static_cast<unsigned long long>(lineno),
                       r.error().message());
        return;
      }
      if (r.value() != can::LogLine::kFrame) return;
      feed(f, t);
      if (count && decoder.estimates >= uint64_t(count)) done = true;
    };
    for (long n; !done && (n = in->read(block, sizeof block)) > 0;) {
      pending.append(block, size_t(n));
      size_t start = 0;
      for (size_t nl; !done && (nl = pending.find('\n', start)) != std::string::npos;
           start = nl + 1) {
        line(std::string_view(pending).substr(start, nl - start));
      }
      pending.erase(0, start);
      if (pending.size() > 4096) {  // no newline for 4 KiB: not a candump log
        line(std::string_view(pending).substr(0, 1024));
        pending.clear();
      }
    }
    if (!done && !pending.empty()) line(pending);
  } else {
    auto sock = can::SocketCan::open(interface, false, true);
    if (!sock) {
      std::fprintf(stderr, "aprt candump: %s\n", sock.error().message());
      return 1;
    }
    std::signal(SIGINT, on_signal);
    std::signal(SIGTERM, on_signal);
    int idle_ms = 0;
    while (!g_stop && (!count || decoder.estimates < uint64_t(count))) {
      can::Frame f;
      int64_t ts = 0;
      const int r = sock.value()->read(&f, 100, &ts);
      if (r < 0 && sock.value()->last_errno() == ENETDOWN) {
        // The interface went down: a receiver waits for it to come back.
        if (!quiet) std::printf("# %s is down\n", interface);
        continue;
      }
      if (r < 0) {
        std::fprintf(stderr, "aprt candump: read from %s failed: %s\n", interface,
                     std::strerror(sock.value()->last_errno()));
        return 1;
      }
      if (r == 0) {
        idle_ms += 100;
        if (timeout_s && idle_ms >= timeout_s * 1000) break;
        continue;
      }
      idle_ms = 0;
      feed(f, double(ts) * 1e-9);
    }
  }
  std::fflush(stdout);
  if (malformed > 5)
    std::fprintf(stderr, "%s: %llu more malformed lines\n", log,
                 static_cast<unsigned long long>(malformed - 5));
  if (frames == 0)
    std::fprintf(stderr, "aprt candump: no CAN frames in %s\n", log ? log : interface);
  const bool lost = decoder.skipped || decoder.incomplete;
  // --strict: a log without a frame, or with a line that is none, fails too.
  const bool bad = decoder.crc_errors || decoder.repeated || printer.disagreements ||
                   (lost && !tolerate_loss) || malformed || frames == 0;
  std::printf("summary: %" PRIu64 " frames, %" PRIu64 " estimates; CRC errors %" PRIu64
              ", repeated counter %" PRIu64 ", skipped counter %" PRIu64
              ", incomplete estimates %" PRIu64 ", error frames %" PRIu64 ", other ids %" PRIu64
              ", malformed lines %" PRIu64 "%s\n",
              frames, decoder.estimates, decoder.crc_errors, decoder.repeated, decoder.skipped,
              decoder.incomplete, error_frames, other, malformed,
              printer.disagreements ? "; DBC/codec DISAGREEMENTS" : "");
  return strict && bad ? 1 : 0;
}

}  // namespace aprt::cli
