#!/usr/bin/env bash
# aprt set-up on Debian 12: installs every package the build, the tools and the
# tests need (idempotent, non-interactive), then configures and builds the
# `release` and `asan` presets. Run from anywhere; needs root or sudo for apt.
set -euo pipefail
cd "$(dirname "$0")/.."

PACKAGES=(
  # build
  build-essential cmake ninja-build pkg-config git
  # tests, sanitizers, fuzzing, formatting
  libgtest-dev libgmock-dev libbenchmark-dev clang clang-format libclang-rt-14-dev
  # runtime libraries: YAML configuration, PNG/JPEG replay, pose geometry, DDS, model signatures
  libyaml-dev libpng-dev libjpeg-dev libeigen3-dev cyclonedds-dev cyclonedds-tools libsodium-dev libcamera-dev libcamera-ipa
  # the Fast DDS peer of the tests (ROS 2's default middleware; tests/peers)
  libfastrtps-dev fastddsgen default-jre-headless util-linux
  # CAN tools (cansend/candump, for the HIL rig and by hand)
  can-utils
  # worst-case timing runs under CPU load (docs/timing.md)
  stress-ng
  # Python tools (Debian's interpreter at /usr/bin/python3); canmatrix is the
  # independent DBC parser of the tests
  python3 python3-numpy python3-torch python3-onnx python3-matplotlib python3-pil
  python3-canmatrix
  # torch links libblas.so.3: OpenBLAS instead of the 10x slower reference BLAS
  libopenblas0-pthread
  # aarch64 cross build, its tests under user-mode emulation
  g++-aarch64-linux-gnu qemu-user
  # the HIL rig: Debian's kernel (downloaded, never installed) under qemu, busybox userland
  qemu-system-x86 busybox-static cpio xz-utils iproute2
)

missing=()
for p in "${PACKAGES[@]}"; do
  dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing+=("$p")
done
# Node.js and npm for the tests' independent MCAP readers (tests/tools/mcap):
# any node >= 18 with npm will do (a machine may carry NodeSource's, whose
# nodejs bundles npm and conflicts with Debian's npm package); Debian's otherwise.
if ! command -v node >/dev/null || ! command -v npm >/dev/null; then
  missing+=(nodejs npm)
fi
if ((${#missing[@]})); then
  SUDO=""
  if [ "$(id -u)" -ne 0 ]; then SUDO="sudo"; fi
  echo "setup: installing ${missing[*]}"
  $SUDO apt-get update -qq
  DEBIAN_FRONTEND=noninteractive $SUDO apt-get install -y -qq --no-install-recommends "${missing[@]}"
fi

# Check what PLATFORM.md warns about: torch on the reference BLAS is ~10x slower.
if ! update-alternatives --query libblas.so.3-x86_64-linux-gnu 2>/dev/null | grep -q "^Value: .*openblas"; then
  echo "setup: warning: libblas.so.3 does not point at OpenBLAS; PyTorch tools will be slow" >&2
fi
/usr/bin/python3 -c "import torch, onnx, numpy" || {
  echo "setup: /usr/bin/python3 cannot import torch/onnx/numpy" >&2
  exit 1
}

# The tests' independent MCAP readers, at the versions package-lock.json pins
# (--ignore-scripts: nothing of theirs runs at install).
if [ ! -d tests/tools/mcap/node_modules/@mcap/core ]; then
  echo "setup: npm packages for tests/tools/mcap"
  (cd tests/tools/mcap && npm ci --ignore-scripts --no-audit --no-fund --loglevel=error)
fi

jobs=$(nproc)
for preset in release asan; do
  cmake --preset "$preset" >/dev/null
  cmake --build --preset "$preset" -j "$jobs"
done
# The LiDAR demo drive (config/lidar_demo.yaml) is rendered, not committed.
tools/synth/lidar_demo_drive.sh data/lidar_demo_drive build/release/bin/aprt_synth
echo "setup: done (build/release/bin/aprt, build/asan/bin/aprt, data/lidar_demo_drive)"
