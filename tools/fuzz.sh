#!/usr/bin/env bash
# Runs aprt's libFuzzer targets (tests/fuzz/, the `fuzz` preset: clang,
# ASan/UBSan), each from its committed seed corpus (tests/fuzz/corpus/TARGET;
# the model-file seeds are written by write_seed). New inputs collect in
# build/fuzz/corpus/TARGET, so a second run continues where the first ended.
#
#   tools/fuzz.sh SECONDS [TARGET...]   each target SECONDS (default: all)
#   tools/fuzz.sh --list
#
# Prints one line per target: executions, seconds, exec/s, corpus size, and
# the exit status (0: no finding; a finding leaves crash-* in build/fuzz/).
set -euo pipefail
cd "$(dirname "$0")/.."
targets=(model_file_fuzz pointcloud2_fuzz pcd_fuzz kitti_fuzz image_fuzz pose_list_fuzz
         frame_sidecar_fuzz candump_log_fuzz config_fuzz dbc_fuzz mcap_fuzz)
if [[ "${1:-}" == "--list" ]]; then printf '%s\n' "${targets[@]}"; exit 0; fi
seconds="${1:?usage: tools/fuzz.sh SECONDS [TARGET...]}"
shift
(($#)) && targets=("$@")
cmake --preset fuzz >/dev/null
cmake --build --preset fuzz -j "$(nproc)" --target "${targets[@]}" write_seed >/dev/null
status=0
for t in "${targets[@]}"; do
  name="${t%_fuzz}"
  corpus="build/fuzz/corpus/$name"
  mkdir -p "$corpus"
  if [[ -d "tests/fuzz/corpus/$name" ]]; then cp -n "tests/fuzz/corpus/$name"/* "$corpus"/; fi
  if [[ "$t" == model_file_fuzz ]]; then build/fuzz/bin/write_seed "$corpus"; fi
  log="build/fuzz/$name.log"
  rc=0
  (cd build/fuzz && "bin/$t" -max_total_time="$seconds" -timeout=10 -rss_limit_mb=4096 \
     -print_final_stats=1 "corpus/$name") >"$log" 2>&1 || rc=$?
  execs=$(sed -n 's/^stat::number_of_executed_units: *//p' "$log" | tail -1)
  rate=$(sed -n 's/^stat::average_exec_per_sec: *//p' "$log" | tail -1)
  printf '%-20s %12s execs %5ss %8s exec/s  corpus %5s  rc %d\n' "$t" "${execs:-?}" "$seconds" \
    "${rate:-?}" "$(ls "$corpus" | wc -l)" "$rc"
  if ((rc != 0)); then
    status=1
    tail -40 "$log"
  fi
done
exit $status
