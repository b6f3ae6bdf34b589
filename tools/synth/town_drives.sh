#!/usr/bin/env bash
# The synthetic town's drives that the shipped model is trained, validated and
# tested on (docs/evaluation.md), rendered into OUT:
#   train_day, train_overcast, train_morning, train_noon  every street both ways,
#       each a different route (seed), lane weaving and light       (~28 600 frames)
#   val_haze   a separate 600 m drive under a light no training drive has (validation)
#   test_dusk  the test drive: 600 m, route seed 7, dusk — the light and the route
#       are in neither set above; identical to the committed data/demo_drive
# Deterministic; ~6 minutes on two cores, ~400 MB.
#   tools/synth/town_drives.sh OUT [path/to/aprt_synth]
set -euo pipefail
out="${1:?usage: town_drives.sh OUT [aprt_synth]}"
synth="${2:-$(dirname "$0")/../../build/release/bin/aprt_synth}"
[ -x "$synth" ] || { echo "town_drives: no aprt_synth at $synth (build the release preset)" >&2; exit 2; }
"$synth" --out "$out/train_day" --split train --route-seed 1 --lighting day --lane-jitter 0.5
"$synth" --out "$out/train_overcast" --split train --route-seed 2 --lighting overcast --lane-jitter 0.8
"$synth" --out "$out/train_morning" --split train --route-seed 3 --lighting morning --lane-jitter 0.6
"$synth" --out "$out/train_noon" --split train --route-seed 4 --lighting noon --lane-jitter 0.9
"$synth" --out "$out/val_haze" --split test --route-seed 11 --lighting haze --max-length 600
"$synth" --out "$out/test_dusk" --split test --route-seed 7 --lighting dusk --max-length 600
