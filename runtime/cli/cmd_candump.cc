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
#include <fstream>
#include <string>

#include "drivers/output/can/dbc.h"
#include "drivers/output/can/pose_can_codec.h"
#include "drivers/output/can/socketcan.h"
#include "runtime/cli/args.h"
#include "runtime/cli/commands.h"
#include "runtime/config/config.h"

namespace aprt::cli {
namespace {

volatile std::sig_atomic_t g_stop = 0;
void on_signal(int) {
  g_stop = 1;
}

int hex_nibble(char c) {
  if (c >= '0' && c <= '9') return c - '0';
  if (c >= 'a' && c <= 'f') return c - 'a' + 10;
  if (c >= 'A' && c <= 'F') return c - 'A' + 10;
  return -1;
}

// One line of `candump -L` ("(1700000000.123456) can0 301#0011..", FD "310##<flags><data>")
// or of candump's default output ("  can0  301   [8]  00 11 ..").
// Returns false for a line that is not a frame.
bool parse_log_line(const std::string& line, can::Frame* f, double* t) {
  *f = can::Frame{};
  *t = 0;
  const size_t hash = line.find('#');
  if (hash != std::string::npos) {
    size_t p = 0;
    if (line[0] == '(') {
      *t = std::strtod(line.c_str() + 1, nullptr);
      p = line.find(')') + 1;
    }
    size_t id_end = hash, id_start = line.rfind(' ', hash);
    id_start = id_start == std::string::npos || id_start < p ? p : id_start + 1;
    f->id = uint32_t(std::strtoul(line.substr(id_start, id_end - id_start).c_str(), nullptr, 16));
    size_t d = hash + 1;
    if (d < line.size() && line[d] == '#') {
      f->fd = true;
      d += 2;  // "##" and the flags nibble
    }
    int n = 0;
    while (d + 1 < line.size() && n < 64) {
      const int hi = hex_nibble(line[d]), lo = hex_nibble(line[d + 1]);
      if (hi < 0 || lo < 0) break;
      f->data[n++] = uint8_t(hi * 16 + lo);
      d += 2;
    }
    f->len = uint8_t(n);
    return true;
  }
  const size_t lb = line.find('['), rb = line.find(']');
  if (lb == std::string::npos || rb == std::string::npos || rb < lb) return false;
  char ifname[32];
  unsigned id = 0;
  if (std::sscanf(line.c_str(), " %31s %x", ifname, &id) != 2) return false;
  f->id = id;
  const int len = std::atoi(line.c_str() + lb + 1);
  f->fd = len > 8;
  const char* p = line.c_str() + rb + 1;
  int n = 0;
  while (*p && n < len && n < 64) {
    while (*p == ' ') ++p;
    const int hi = hex_nibble(p[0]), lo = p[0] ? hex_nibble(p[1]) : -1;
    if (hi < 0 || lo < 0) break;
    f->data[n++] = uint8_t(hi * 16 + lo);
    p += 2;
  }
  f->len = uint8_t(n);
  return true;
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
    const double yaw =
        std::atan2(2 * (s.qw * s.qz + s.qx * s.qy), 1 - 2 * (s.qy * s.qy + s.qz * s.qz));
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
        "  --strict        exit 1 if any CRC, counter or grouping error was seen\n"
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
  if (log) {
    std::ifstream in(log);
    if (!in) {
      std::fprintf(stderr, "aprt candump: cannot open '%s'\n", log);
      return 2;
    }
    std::string line;
    while (std::getline(in, line)) {
      can::Frame f;
      double t;
      if (!parse_log_line(line, &f, &t)) continue;
      // candump -L marks error frames with the CAN_ERR_FLAG bit in the id.
      feed(f, t);
      if (count && decoder.estimates >= uint64_t(count)) break;
    }
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
  const bool lost = decoder.skipped || decoder.incomplete;
  const bool bad =
      decoder.crc_errors || decoder.repeated || printer.disagreements || (lost && !tolerate_loss);
  std::printf("summary: %" PRIu64 " frames, %" PRIu64 " estimates; CRC errors %" PRIu64
              ", repeated counter %" PRIu64 ", skipped counter %" PRIu64
              ", incomplete estimates %" PRIu64 ", error frames %" PRIu64 ", other ids %" PRIu64
              "%s\n",
              frames, decoder.estimates, decoder.crc_errors, decoder.repeated, decoder.skipped,
              decoder.incomplete, error_frames, other,
              printer.disagreements ? "; DBC/codec DISAGREEMENTS" : "");
  return strict && bad ? 1 : 0;
}

}  // namespace aprt::cli
