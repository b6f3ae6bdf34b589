// aprt's configuration: the typed form of the YAML file `aprt run --config`
// reads (schema and defaults: docs/configuration.md). Every key is checked:
// unknown keys, wrong types and out-of-range values are refused with the key
// path and line ("aprt.yaml:12: source.replay.rate_hz: expected a number in
// [0, 1000], got 'fast'").
#pragma once

#include <string>
#include <vector>

#include "drivers/input/can_odometry/can_odometry.h"
#include "runtime/base/expected.h"
#include "runtime/config/fault_spec.h"
#include "runtime/pose/pose_filter.h"

namespace aprt {

// Where frames come from: camera frames (replay, v4l2, libcamera) or LiDAR
// scans (lidar_replay, pointcloud2). Parsed once from source.type.
enum class SourceType : uint8_t { kReplay, kV4l2, kLibcamera, kLidarReplay, kPointCloud2, kMcap };
const char* source_type_name(SourceType t);
// false for a name that is none of the above.
bool source_type_from_name(const std::string& name, SourceType* out);

struct ThreadConfig {
  int priority = 0;  // SCHED_FIFO priority 1..99; 0 = normal scheduling
  int cpu = -1;      // pin to this CPU; -1 = no pinning
};

struct Config {
  std::string origin = "<defaults>";  // where it came from, for messages
  std::string model;

  // Test rigs only: deliberate faults (runtime/config/fault_spec.h).
  std::vector<FaultSpec> fault_injection;

  // Ed25519 signatures over model files (runtime/loop/model_signature.h).
  struct ModelSigning {
    std::string public_key;  // key file from `aprt sign keygen`; empty: signatures not checked
    bool required = false;   // true: an unsigned or wrongly signed model is refused
  } model_signing;

  struct Engine {
    int threads = 1;
    std::string isa = "auto";
    std::vector<int> cpus;  // worker pinning
  } engine;

  struct Source {
    SourceType type = SourceType::kReplay;
    struct Replay {
      std::string path;
      double rate_hz = 10.0;  // 0: as fast as inference takes frames; "recorded": times.txt
      bool recorded = false;
      bool loop = false;
      int frames = 0;  // stop after this many frames (0: the whole sequence, or forever with loop)
    } replay;          // also lidar_replay's: path is the LiDAR sequence (lidar_poses.txt + scans)
                       // and mcap's: path is the .mcap file
    struct Mcap {
      std::string topic;  // the image or point-cloud channel; empty: the file's first
    } mcap;
    struct V4l2 {
      std::string device = "/dev/video0";
      int width = 640, height = 480;
      std::string format = "YUYV";
      int fps = 30;
      int buffers = 4;
      int frames = 0;  // stop after this many frames (0: run until stopped)
    } v4l2;
    struct Libcamera {
      std::string camera;  // id or index; empty: the first camera
      int width = 640, height = 480;
      std::string format = "YUYV";
      std::string role = "viewfinder";  // viewfinder | video | still
      int fps = 30;
      int buffers = 4;
      int frames = 0;  // stop after this many frames (0: run until stopped)
    } libcamera;
    struct PointCloud2 {                  // sensor_msgs/msg/PointCloud2 over DDS
                                          // (drivers/input/pointcloud2/pointcloud2_reader.h)
      std::string topic = "/points_raw";  // ROS name ("rt" is prepended)
      int domain = 0;
      bool reliable = false;  // ROS 2 sensor-data QoS: best effort
      int depth = 5;
      bool loopback_only = false;
      int frames = 0;  // stop after this many scans (0: run until stopped)
    } pointcloud2;
    struct Lidar {              // every LiDAR source: the point buffer and its gate
      int max_points = 200000;  // more in one scan are dropped and counted
      // points outside are clipped onto the box (and counted)
      double region[6] = {-200, 200, -200, 200, -20, 40};  // x_min x_max y_min y_max z_min z_max
      int min_points = 1;  // a scan with fewer points is flagged sparse (points models: also
                           // any scan with fewer points than the model samples)
    } lidar;
    bool lidar_source() const {
      return type == SourceType::kLidarReplay || type == SourceType::kPointCloud2;
    }
    // A recorded sequence (camera or LiDAR), paced by aprt; not a device.
    bool replay_source() const {
      return type == SourceType::kReplay || type == SourceType::kLidarReplay ||
             type == SourceType::kMcap;
    }
  } source;

  // Several cameras, fused into one pose (runtime/pose/pose_fusion.h). Empty:
  // one camera, `source` with `extrinsics.sensor_to_base_link`. When the
  // configuration lists cameras, `source` and the sensor extrinsic mirror the
  // first one (the trigger: its frames start each fusion cycle).
  struct Camera {
    std::string name;
    Source source;
    double sensor_xyz[3] = {0, 0, 0};
    double sensor_rpy_deg[3] = {0, 0, 0};
  };
  static constexpr int kMaxCameras = 8;
  std::vector<Camera> cameras;

  struct Fusion {
    double max_position_spread_m = 5.0;  // an estimate this far from the consensus is an outlier
    double max_orientation_spread_deg = 10.0;  // ... or this far in orientation
    int min_agreeing = 1;             // at least this many agreeing cameras (and always a majority)
    double max_frame_skew_ms = 20.0;  // wait this long after the trigger for the others' frames
    // A second sensor with its own model (runtime/loop/companion.h): the path
    // of its own configuration file (its model, source, extrinsics and
    // validity gate; relative to this file). Empty: none.
    std::string companion;
    double companion_max_age_ms = 150.0;  // an older companion estimate is not fused
    double min_lead_s = 1.0;   // two valid sensors that disagree: the longer valid by this much
    bool cross_check = false;  // one valid sensor checked against the other's estimate too
  } fusion;

  struct Output {
    bool console = true;  // a line per pose (with errors when the source has ground truth)
    bool summary = true;  // statistics at exit
    std::string frame_id = "map";
    // 1-sigma of the published covariance; 0: the model's measured validation error.
    double sigma_position_m = 0.0, sigma_orientation_deg = 0.0;
    double status_rate_hz = 1.0;  // diagnostics / status
    // Per-pose records (timing and errors) kept for the summary and --timing
    // when the run's length is not known (a live source): the first N poses,
    // 48 bytes each, preallocated and, with lock_memory, locked. 65536: 36 min
    // at 30 Hz, 3 MiB.
    int records = 65536;
    struct Dds {
      bool enabled = false;
      int domain = 0;
      std::string pose_topic = "/aprt/pose_with_covariance";  // ROS name ("rt" is prepended)
      std::string diagnostics_topic = "/diagnostics";
      std::string reliability = "reliable";  // reliable | best_effort
      int depth = 10;
      bool loopback_only = false;
      int discovery_wait_ms = 1500;  // before the first pose: peers' endpoints known
    } dds;
    struct Can {
      bool enabled = false;
      std::string interface = "can0";
      bool fd = false;        // one CAN FD frame instead of five classic frames
      double cycle_ms = 0.0;  // at most one estimate per cycle; 0: every estimate
      double recover_ms = 1000.0;
      // status, pos_xy, pos_zqw, quat_yz, time, fd (config/aprt_pose.dbc)
      int ids[6] = {0x300, 0x301, 0x302, 0x303, 0x304, 0x310};
    } can;
  } output;

  // Where the sensor sits on the vehicle and how the training map frame maps
  // to the ECU's (runtime/pose/pose_geometry.h).
  struct Extrinsics {
    double sensor_xyz[3] = {0, 0, 0};      // sensor origin in base_link, metres
    double sensor_rpy_deg[3] = {0, 0, 0};  // roll pitch yaw of the sensor in base_link
    double map_offset_xyz[3] = {0, 0, 0};
    double map_offset_rpy_deg[3] = {0, 0, 0};
  } extrinsics;

  struct Supervisor {
    double rate_hz = 50.0;
    double frame_timeout_ms = 1000.0;  // no new frame for this long: DEGRADED
    double inference_deadline_ms = 200.0;
    double fault_after_s = 10.0;  // DEGRADED this long: FAULT
    std::string watchdog_device;  // e.g. /dev/watchdog; empty: none
    int watchdog_timeout_s = 5;
    bool systemd = true;  // sd_notify READY/WATCHDOG/STATUS if NOTIFY_SOCKET is set
  } supervisor;

  struct Sanity {
    double bounds_margin = 0.1;   // of the map extent, each side
    double max_jump_m = 30.0;     // between consecutive poses (0: off)
    double max_speed_mps = 60.0;  // jump allowance grows with time since the last pose
    // The validity gate (runtime/pose/pose_gate.h): the model's own confidence
    // and the agreement with the vehicle's motion decide what goes out valid.
    struct Track {
      bool enabled = true;
      double max_radius_m = 8.0;  // 95 % horizontal radius the model may state
      double max_yaw_deg = 10.0;  // 95 % yaw half-interval the model may state
      double gate_m = 6.0;        // from the track's constant-velocity prediction
      double gate_deg = 10.0;
      double gate_growth_mps = 2.0;  // the gate widens with the time since the last accepted
      int confirm = 5;               // consistent estimates in a row that start a track
      int lost_after = 25;           // refusals in a row that end it
    } track;
    // The pose filter (runtime/pose/pose_filter.h): with the vehicle's
    // odometry, the published pose is the filter's, valid by its own
    // covariance. It chooses its measurements with its own limits on the
    // model's stated confidence (the track's stay strict for a run without
    // odometry, where the gate alone decides): PoseFilterParams, and the two
    // limits on the estimates it takes at all (EstimateLimits).
    struct Filter : PoseFilterParams, EstimateLimits {
    } filter;
  } sanity;

  // Where the pose filter (sanity.filter) gets the vehicle's motion.
  struct Odometry {
    // replay: a replayed drive's odometry.txt; dds: a ROS 2 topic of
    // geometry_msgs/msg/TwistWithCovarianceStamped (drivers/input/twist/);
    // can: the vehicle's speed and yaw-rate signals on its CAN bus, located
    // by its DBC file (drivers/input/can_odometry/).
    std::string source = "replay";
    std::string topic = "/sensing/vehicle_velocity_converter/twist_with_covariance";
    int domain = 0;
    bool reliable = true;
    bool loopback_only = false;
    int depth = 50;
    CanOdometryOptions can;  // drivers/input/can_odometry/can_odometry.h
  } odometry;

  struct Threads {
    ThreadConfig capture, inference, publish, supervisor;
    bool lock_memory = true;  // mlockall
    int stack_kib = 512;      // every thread's stack, ours and the DDS library's
  } threads;
};

// The cameras the loop runs: `cameras`, or the single `source` with the
// sensor extrinsic when the configuration names none.
std::vector<Config::Camera> camera_list(const Config& c);

// Parses and validates a YAML file.
Expected<Config> load_config(const std::string& path);
Expected<Config> parse_config(const std::string& text, const std::string& origin);

}  // namespace aprt
