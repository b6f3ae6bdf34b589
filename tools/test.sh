#!/usr/bin/env bash
# aprt tests.
#   tools/test.sh            the default run: format and layer checks, then every
#                            test except the slow suites, on the ASan+UBSan build
#   tools/test.sh --slow     full-size golden models (224 and 128) on the release build
#   tools/test.sh --fuzz N   every libFuzzer target (tools/fuzz.sh) in N seconds in all (clang)
#   tools/test.sh --tsan     the threaded engine and the supervised loop under ThreadSanitizer
#   tools/test.sh --aarch64  cross build for aarch64; unit, kernel and tiny golden
#                            tests under qemu-aarch64 as Cortex-A76 (dotprod), then
#                            those whose kernels the CPU picks as Cortex-A72 (no dotprod)
#   tools/test.sh --package  .deb packages (amd64; arm64 when the aarch64 build
#                            exists): contents, scratch-root install, aprt info,
#                            aprt run, find_package(aprt) from another project
#   tools/test.sh --plain    integrator builds: plain CMake (no presets) in Release with
#                            GCC and with clang, distribution flags added; cmake
#                            --install against the packages' file list
#   tools/test.sh --hil [S]  the HIL scenarios (tests/hil: SocketCAN on vcan, softdog)
#                            in a Debian-kernel VM under qemu; S: one scenario
# Run tools/setup.sh first (it installs and builds).
set -euo pipefail
cd "$(dirname "$0")/.."
jobs=$(nproc)

case "${1:-}" in
  "")
    tools/check_format.sh
    tools/check_layers.py
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
    # Every libFuzzer target (tools/fuzz.sh), SECONDS split among them:
    # the model file a third, the other ten the rest.
    seconds="${2:-60}"
    tools/fuzz.sh "$((seconds / 3 > 1 ? seconds / 3 : 1))" model_file_fuzz
    rest=$(( (seconds * 2 / 3) / 10 ))
    tools/fuzz.sh "$((rest > 1 ? rest : 1))" pointcloud2_fuzz pcd_fuzz kitti_fuzz image_fuzz \
      pose_list_fuzz frame_sidecar_fuzz candump_log_fuzz config_fuzz dbc_fuzz mcap_fuzz
    ;;
  --tsan)
    cmake --preset tsan >/dev/null
    cmake --build --preset tsan -j "$jobs" --target unit_tests kernel_tests run_loop_tests dds_tests
    TSAN_OPTIONS="halt_on_error=1" build/tsan/bin/unit_tests --gtest_filter='Engine.*'
    # The odometry thread handing twists to the inference thread (odometry.source dds).
    TSAN_OPTIONS="halt_on_error=1 suppressions=$PWD/tests/tsan.supp" build/tsan/bin/dds_tests \
      --gtest_filter='Dds.OdometryInput*:Dds.TheFilterRunsOnLiveOdometry'
    # The supervised loop's four threads, end to end: its fixtures (tiny model,
    # synthetic drive) come from the default run's build.
    cmake --preset asan >/dev/null
    cmake --build --preset asan -j "$jobs" --target aprt_synth >/dev/null
    ctest --preset asan -R 'run\.(replay|lidar)\.generate' --timeout 600 >/dev/null
    TSAN_OPTIONS="halt_on_error=1 suppressions=$PWD/tests/tsan.supp" \
      APRT_RUN_FIXTURES="$PWD/build/asan" build/tsan/bin/run_loop_tests \
      --gtest_filter='RunLoop.*:MultiCamera.*:LidarLoop.*:Companion.*'
    # (FaultInjection.* is timing-driven by design; it runs in the default step.)
    ;;
  --aarch64)
    tools/aarch64_sysroot.sh
    cmake --preset aarch64 >/dev/null
    cmake --build --preset aarch64 -j "$jobs"
    echo "== aarch64 tests as cortex-a76 (dotprod)"
    QEMU_CPU=cortex-a76 ctest --preset aarch64 -L "unit|kernels|golden" --timeout 900
    # The A72 has no dotprod: again every test whose kernels the CPU picks.
    # The reference kernels' golden runs and the PyTorch generation of the
    # golden data (native Python, the CPU's no matter) ran above; their
    # files are reused.
    echo "== aarch64 tests as cortex-a72 (no dotprod): the CPU-picked paths"
    QEMU_CPU=cortex-a72 ctest --preset aarch64 -L "unit|kernels|golden" -E '\.(ref|generate|convert)$' \
      --fixture-exclude-setup '^golden_' --timeout 900
    ;;
  --package)
    cmake --preset release >/dev/null
    cmake --build --preset release -j "$jobs" --target aprt
    tools/package_smoke.sh release
    if [ -x build/aarch64/bin/aprt ]; then
      cmake --preset aarch64 >/dev/null
      tools/package_smoke.sh aarch64
    fi
    ;;
  --plain)
    tools/plain_build.sh gcc Release
    tools/plain_build.sh clang Release
    ;;
  --hil)
    cmake --preset release >/dev/null
    cmake --build --preset release -j "$jobs" --target aprt aprt_synth
    shift
    tests/hil/run.sh "$@"
    ;;
  *)
    echo "usage: tools/test.sh [--slow | --fuzz SECONDS | --tsan | --aarch64 | --package | --plain | --hil [SCENARIO]]" >&2
    exit 2
    ;;
esac
