#!/usr/bin/env bash
# The synthetic town's LiDAR drives that the shipped BEV model is trained,
# validated and tested on (docs/evaluation.md, "The LiDAR model"), rendered into
# OUT. The same routes and the same split as the camera's (town_drives.sh):
#   lidar_train_route{1,2,3,4}        every street both ways, lane weaving
#   lidar_train_jitter_route{5,6,8,9} the same with a per-scan view change:
#       +-1.5 m across the lane, +-10 deg in yaw (height and pitch move only
#       the camera)                                               (~59 000 scans)
#   lidar_val_route{11..19}  the nine validation routes (600 m): choose, calibrate
#   lidar_test_route7        the camera demo drive's route (test)
#   lidar_test_route{21,22,23}  the camera's unseen test routes
#   test_night_route25  the night test drive, camera and LiDAR along the same
#       unseen route (street lights only): the case the paper makes for LiDAR
# Scans only (--no-images) except the night drive; light does not change a
# scan. Test drives are looked at once per shipped model.
# Deterministic; ~5 minutes on two cores, ~27 GB (0.45 MB a scan).
#   tools/synth/town_lidar_drives.sh OUT [path/to/aprt_synth] [--only NAME]
script=town_lidar_drives
extra="--lidar"
# shellcheck source=tools/synth/render_drives.sh
source "$(dirname "$0")/render_drives.sh"
scans="--no-images"
render lidar_train_route1 --split train --route-seed 1 --lane-jitter 0.5 $scans
render lidar_train_route2 --split train --route-seed 2 --lane-jitter 0.8 $scans
render lidar_train_route3 --split train --route-seed 3 --lane-jitter 0.6 $scans
render lidar_train_route4 --split train --route-seed 4 --lane-jitter 0.9 $scans
for seed in 5 6 8 9; do
  render lidar_train_jitter_route$seed --split train --route-seed $seed --view-jitter 1.5,0,0,10 $scans
done
for seed in 11 12 13 14 15 16 17 18 19; do
  render lidar_val_route$seed --split test --route-seed $seed --max-length 600 $scans
done
for seed in 7 21 22 23; do
  render lidar_test_route$seed --split test --route-seed $seed --max-length 600 $scans
done
render test_night_route25 --split test --route-seed 25 --lighting night --max-length 600
