#!/usr/bin/env bash
# The night demo drive of config/lidar_demo.yaml and config/fused_demo.yaml:
# the night test drive's route (seed 25, 600 m; docs/evaluation.md, "The
# LiDAR model"), its scans and its camera frames along the same poses. Made
# here rather than committed: 587 scans of ~22 000 points are ~240 MB, and the
# renderer makes the same files from these arguments in ~15 seconds.
# tools/setup.sh runs this after building; the tests make its first FRAMES.
#   tools/synth/lidar_demo_drive.sh [OUT] [path/to/aprt_synth] [FRAMES]
set -euo pipefail
root="$(cd "$(dirname "$0")/../.." && pwd)"
out="${1:-$root/data/lidar_demo_drive}"
synth="${2:-$root/build/release/bin/aprt_synth}"
frames="${3:-0}"  # 0: the whole drive
[ -x "$synth" ] || { echo "lidar_demo_drive: no aprt_synth at $synth (build the release preset)" >&2; exit 2; }
if [ -f "$out/dataset.json" ] && [ -f "$out/lidar_poses.txt" ] && [ -d "$out/images" ]; then
  echo "lidar_demo_drive: $out exists"
  exit 0
fi
rm -rf "$out.partial"
"$synth" --quiet --out "$out.partial" --split test --route-seed 25 --lighting night \
  --max-length 600 --lidar --frames "$frames"
rm -rf "$out"
mv "$out.partial" "$out"
echo "lidar_demo_drive: $out"
