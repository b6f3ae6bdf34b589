// Where a pose goes after the console: base_link in the ECU's map frame
// (PoseGeometry), then DDS (PoseWithCovarianceStamped + DiagnosticArray) and
// CAN (config/aprt_pose.dbc). Created before the loop starts; an output that
// cannot start (no DDS, no SocketCAN, CAN interface missing) is reported with
// its reason and the rest keeps running -- a missing CAN interface is retried
// per recover interval, since a CAN driver may come up after aprt.
//
// Validity: DDS's message has no validity field, so a flagged estimate is
// never published on the pose topic (the diagnostics say why); on CAN it goes
// out with Valid = 0 and its flags.
#pragma once

#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "drivers/can/socketcan.h"
#include "drivers/output/can/pose_can_sender.h"
#include "runtime/config/config.h"
#include "runtime/engine/model_file.h"
#include "runtime/loop/pose_record.h"
#include "runtime/pose/pose_geometry.h"

namespace aprt {

class Recorder;

class DdsPublisher;

struct OutputStats {
  uint64_t dds_poses = 0, dds_withheld = 0, dds_errors = 0, dds_status = 0;
  // Why poses were withheld: the supervisor not RUNNING, and each flag (a
  // pose may count under several).
  uint64_t dds_withheld_not_running = 0;
  uint64_t dds_withheld_flag[16] = {};
  uint64_t can_sent = 0, can_throttled = 0, can_dropped = 0;
};

// The summary's breakdown of withheld poses: " (12 supervisor not RUNNING;
// 30 unconfirmed, 4 uncertain)", or "" when none was withheld.
void withheld_reasons(const OutputStats& st, char* buf, size_t size);

// What the status message reports besides the outputs' own counters.
struct StatusSnapshot {
  RunState state = RunState::kStarting;
  const char* reason = "";
  uint64_t poses = 0, flagged = 0, deadline_misses = 0, frames_skipped = 0;
  uint32_t last_flags = 0;
  double last_inference_ms = 0;
  const FusionSummary* fusion = nullptr;     // the last cycle's (multi-camera runs)
  const CompanionNote* companion = nullptr;  // the last cycle's (fusion.companion runs)
  const FilterNote* filter = nullptr;        // the last cycle's (sanity.filter runs)
  // LiDAR runs: the last scan's points (after a points model's crop), what the
  // point gate dropped and clipped in it, and the sparse scans so far.
  bool lidar = false;
  uint32_t scan_points = 0, scan_dropped = 0, scan_clipped = 0;
  uint64_t sparse_scans = 0;
};

class PoseOutputs {
 public:
  static Expected<std::unique_ptr<PoseOutputs>> create(const Config& config, const ModelMeta& meta);
  ~PoseOutputs();

  // @rt. now_ns: CLOCK_MONOTONIC; realtime_offset_ns: CLOCK_REALTIME - CLOCK_MONOTONIC.
  void publish(const PoseRecord& r, int64_t now_ns, int64_t realtime_offset_ns) noexcept;
  // @rt. At output.status_rate_hz (the caller paces it).
  void publish_status(const StatusSnapshot& s, int64_t realtime_ns) noexcept;

  const OutputStats& stats() const { return stats_; }
  const can::SenderStats* can_stats() const;
  bool dds_active() const { return dds_ != nullptr; }
  // Every pose and diagnostics message also goes to `r` (recorder.h), from
  // the publisher thread. Set before the run starts.
  void set_recorder(Recorder* r) { recorder_ = r; }
  bool can_active() const { return can_sender_ != nullptr; }
  // The last base_link pose computed (for tests and the console).
  const BasePose& last_base_pose() const { return last_; }
  void print_summary() const;

 private:
  PoseOutputs() = default;
  Config::Output cfg_;
  std::unique_ptr<PoseGeometry> geometry_;
  double sigma_pos_ = 0, sigma_rot_deg_ = 0;
  std::unique_ptr<DdsPublisher> dds_;
  Recorder* recorder_ = nullptr;
  std::unique_ptr<can::SocketCan> can_socket_;
  std::unique_ptr<can::PoseCanSender> can_sender_;
  BasePose last_{};
  OutputStats stats_;
  std::string dds_off_reason_, can_off_reason_;
  std::vector<std::string> camera_keys_;  // "camera NAME" per fused camera
};

}  // namespace aprt
