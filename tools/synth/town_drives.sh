#!/usr/bin/env bash
# The synthetic town's drives that the shipped model is trained, validated and
# tested on (docs/evaluation.md), rendered into OUT:
#   train_day, train_overcast, train_morning, train_noon  every street both ways,
#       each a different route (seed), lane weaving and light       (~28 600 frames)
#   train_jitter_{day,overcast,morning,noon}  four more such routes (seeds 5, 6, 8, 9)
#       whose every frame is a perturbed view: +-1.5 m across the lane, camera
#       +-0.3 m in height, +-3 deg in pitch, +-10 deg in yaw        (~28 600 frames)
#   train_route{26,27,28,29}_{day,overcast,morning,noon}  four more routes, every
#       frame a milder perturbed view (+-1 m, +-0.2 m, +-2 deg, +-6 deg): added for
#       the fourth continued run (docs/evaluation.md; its model is the
#       shipped model_bin/town_64.aprt)
#   train_route{30,31,32,33}_{day,overcast,morning,noon}  four more such routes,
#       added for the fifth continued run (docs/evaluation.md)
#   train_route{34..41}_{day,overcast,morning,noon}  eight more such routes (two
#       per light), added for the eighth continued run (docs/evaluation.md)
#   train_route{42..49}_{day,morning,noon}_lowsun  eight more such routes, each
#       with the sun moved low (10-25 deg) to a different azimuth (--sun), added
#       for the ninth continued run (docs/evaluation.md)
#   val_haze   a separate 600 m drive under a light no training drive has (validation)
#   val_route12_morning  a second validation drive: route seed 12, morning light
#   val_route13_dusk     a third: route seed 13, dusk light
#   val_route14_haze ... val_route19_day  six more (route seeds 14-19, one light
#       each): the validity gate's wrong poses are rare events, so it is chosen
#       on all the validation drives (nine, ~5 200 frames; fourteen since the
#       eleventh step)
#   val_route{50..53}_dusk  four more dusk validation drives (route seeds 50-53)
#   val_mount_low  route 54 by day, the camera mounted 0.2 m lower than in training
#   test_dusk  the test drive: 600 m, route seed 7, dusk — the light and the route
#       are in neither set above; identical to the committed data/demo_drive
#   test_route21_noon, test_route22_dusk, test_route23_haze  unseen routes (600 m)
#   test_mount_high  unseen route 24 by day, the camera mounted 0.25 m higher
# Test drives are looked at once per shipped model; choices use the val_ drives
# (the confidence is calibrated on val_haze, the filter's keys chosen on all fourteen).
# Deterministic; ~40 minutes on two cores, ~2 GB.
#   tools/synth/town_drives.sh OUT [path/to/aprt_synth] [--only NAME]
script=town_drives
extra=""
# shellcheck source=tools/synth/render_drives.sh
source "$(dirname "$0")/render_drives.sh"
jitter=1.5,0.3,3,10
render train_day      --split train --route-seed 1 --lighting day --lane-jitter 0.5
render train_overcast --split train --route-seed 2 --lighting overcast --lane-jitter 0.8
render train_morning  --split train --route-seed 3 --lighting morning --lane-jitter 0.6
render train_noon     --split train --route-seed 4 --lighting noon --lane-jitter 0.9
render train_jitter_day      --split train --route-seed 5 --lighting day --view-jitter $jitter
render train_jitter_overcast --split train --route-seed 6 --lighting overcast --view-jitter $jitter
render train_jitter_morning  --split train --route-seed 8 --lighting morning --view-jitter $jitter
render train_jitter_noon     --split train --route-seed 9 --lighting noon --view-jitter $jitter
mild=1.0,0.2,2,6
render train_route26_day      --split train --route-seed 26 --lighting day --view-jitter $mild
render train_route27_overcast --split train --route-seed 27 --lighting overcast --view-jitter $mild
render train_route28_morning  --split train --route-seed 28 --lighting morning --view-jitter $mild
render train_route29_noon     --split train --route-seed 29 --lighting noon --view-jitter $mild
render train_route30_day      --split train --route-seed 30 --lighting day --view-jitter $mild
render train_route31_overcast --split train --route-seed 31 --lighting overcast --view-jitter $mild
render train_route32_morning  --split train --route-seed 32 --lighting morning --view-jitter $mild
render train_route33_noon     --split train --route-seed 33 --lighting noon --view-jitter $mild
lights=(day overcast morning noon)
for seed in 34 35 36 37 38 39 40 41; do
  light=${lights[$(((seed - 34) % 4))]}
  render "train_route${seed}_$light" --split train --route-seed $seed --lighting "$light" --view-jitter $mild
done
# Low sun from every side (--sun): the training presets' suns stand at four
# azimuths and 22-72 deg, so their shadows fall four ways; a low sun's long
# shadows from other sides are what the unseen lights (haze, dusk) add, and
# the dusk drives were where the eighth run did worst.
# The sun's colours stay the preset's; no route here uses the haze or dusk preset.
# Eight azimuths 45 deg apart from east, elevations 10 + 7k mod 20 deg.
suns=(0,10 45,17 90,24 135,11 180,18 225,25 270,12 315,19)
sun_lights=(day morning noon day morning noon day morning)
for k in 0 1 2 3 4 5 6 7; do
  seed=$((42 + k))
  render "train_route${seed}_${sun_lights[$k]}_lowsun" --split train --route-seed $seed \
    --lighting "${sun_lights[$k]}" --sun "${suns[$k]}" --view-jitter $mild
done
render val_haze   --split test --route-seed 11 --lighting haze --max-length 600
render val_route12_morning --split test --route-seed 12 --lighting morning --max-length 600
render val_route13_dusk --split test --route-seed 13 --lighting dusk --max-length 600
render val_route14_haze     --split test --route-seed 14 --lighting haze --max-length 600
render val_route15_noon     --split test --route-seed 15 --lighting noon --max-length 600
render val_route16_overcast --split test --route-seed 16 --lighting overcast --max-length 600
render val_route17_morning  --split test --route-seed 17 --lighting morning --max-length 600
render val_route18_dusk     --split test --route-seed 18 --lighting dusk --max-length 600
render val_route19_day      --split test --route-seed 19 --lighting day --max-length 600
# Four more dusk validation drives and one with the camera mounted lower: the
# dusk drives are where files better on the first nine did worse on the test
# drives (docs/evaluation.md, "Eleventh step"), and no validation drive had a
# mount other than training's while a test drive has.
for seed in 50 51 52 53; do
  render "val_route${seed}_dusk" --split test --route-seed $seed --lighting dusk --max-length 600
done
render val_mount_low --split test --route-seed 54 --lighting day --max-length 600 \
  --camera-mount 1.2,0,1.35,3
render test_dusk  --split test --route-seed 7 --lighting dusk --max-length 600
render test_route21_noon --split test --route-seed 21 --lighting noon --max-length 600
render test_route22_dusk --split test --route-seed 22 --lighting dusk --max-length 600
render test_route23_haze --split test --route-seed 23 --lighting haze --max-length 600
render test_mount_high   --split test --route-seed 24 --lighting day --max-length 600 \
  --camera-mount 1.2,0,1.80,3
