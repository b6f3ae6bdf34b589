#!/usr/bin/env bash
# aprt tests.
#   tools/test.sh            the default run: format check, then every test except
#                            the slow suites, on the ASan+UBSan build (~1 minute)
#   tools/test.sh --slow     full-size golden models (224 and 128) on the release build
#   tools/test.sh --fuzz N   the model-file fuzzer for N seconds (clang, libFuzzer)
# Run tools/setup.sh first (it installs and builds).
set -euo pipefail
cd "$(dirname "$0")/.."
jobs=$(nproc)

case "${1:-}" in
  "")
    tools/check_format.sh
    cmake --preset asan >/dev/null
    cmake --build --preset asan -j "$jobs"
    ctest --preset asan -LE slow --timeout 900
    ;;
  --slow)
    cmake --preset release >/dev/null
    cmake --build --preset release -j "$jobs"
    ctest --preset release -L slow --timeout 1800
    ;;
  --fuzz)
    seconds="${2:-60}"
    cmake --preset fuzz >/dev/null
    cmake --build --preset fuzz -j "$jobs"
    corpus=build/fuzz/corpus
    mkdir -p "$corpus"
    build/fuzz/bin/write_seed "$corpus"
    build/fuzz/bin/model_file_fuzz -max_total_time="$seconds" -timeout=10 -rss_limit_mb=4096 \
      -print_final_stats=1 "$corpus"
    ;;
  *)
    echo "usage: tools/test.sh [--slow | --fuzz SECONDS]" >&2
    exit 2
    ;;
esac
