# Sourced by town_drives.sh and town_lidar_drives.sh: their arguments
# (OUT [path/to/aprt_synth] [--only NAME]) and `render NAME ARGS...`, which
# makes OUT/NAME with aprt_synth unless it is there already (or --only names
# another drive), with its odometry.txt (python3 -m aprt_tools odometry).
# $script names the caller in messages; $extra holds options every drive of
# the caller takes.
set -euo pipefail
out="${1:?usage: $script OUT [aprt_synth] [--only NAME]}"
synth="${2:-$(dirname "${BASH_SOURCE[0]}")/../../build/release/bin/aprt_synth}"
only="${4:-}"
[ -x "$synth" ] || { echo "$script: no aprt_synth at $synth (build the release preset)" >&2; exit 2; }
render() {
  local name="$1"; shift
  if [ -n "$only" ] && [ "$only" != "$name" ]; then return; fi
  if [ -f "$out/$name/dataset.json" ]; then echo "$script: $name exists"; return; fi
  # shellcheck disable=SC2086 # $extra is a list of options
  "$synth" --quiet $extra --out "$out/$name" "$@"
  # The speed and yaw rate its vehicle would report (the pose filter's input),
  # errors drawn from a seed of the drive's name.
  if [ -f "$out/$name/poses.txt" ]; then
    PYTHONPATH="$(dirname "${BASH_SOURCE[0]}")/.." "${APRT_PYTHON:-/usr/bin/python3}" -m aprt_tools odometry "$out/$name" \
      --seed "$(echo "$name" | cksum | cut -c1-5)" >/dev/null
  fi
}
