#!/usr/bin/env bash
# Integrator builds: plain CMake as Yocto, Buildroot or a distribution's
# packaging runs it -- no presets, its own compiler and flags added:
#   tools/plain_build.sh [gcc|clang] [Release|RelWithDebInfo|MinSizeRel]
# 1. configures with only CMAKE_BUILD_TYPE, the compiler and hardening flags
#    of the kind dpkg-buildflags adds (warnings stay warnings: APRT_WERROR is
#    off unless asked for), builds aprt and the engine's libraries
# 2. `cmake --install` into a scratch root (DESTDIR) and checks that it holds
#    exactly the files of the .deb packages cpack makes from the same build
# 3. the installed aprt checks the installed ECU configuration and replays
#    a few frames of the demo drive with no options
set -euo pipefail
cd "$(dirname "$0")/.."
compiler="${1:-gcc}"
type="${2:-Release}"
fail() { echo "plain_build: $*" >&2; exit 1; }
case "$compiler" in
  gcc) cc=gcc cxx=g++ ;;
  clang) cc=clang cxx=clang++ ;;
  *) fail "compiler '$compiler': gcc or clang" ;;
esac
case "$type" in Release | RelWithDebInfo | MinSizeRel) ;; *) fail "build type '$type'" ;; esac
build="build/plain-$compiler-$type"
flags="-fstack-protector-strong -D_FORTIFY_SOURCE=2 -Wformat -Werror=format-security"
rm -rf "$build"
echo "== $compiler $type: cmake -S . -B $build (no preset), CXXFLAGS: $flags"
CC=$cc CXX=$cxx cmake -S . -B "$build" -DCMAKE_BUILD_TYPE="$type" -DCMAKE_CXX_FLAGS="$flags" \
  -DAPRT_BUILD_TESTS=OFF -DAPRT_BUILD_BENCHMARKS=OFF -DAPRT_BUILD_TOOLS=OFF >/dev/null
cmake --build "$build" -j "$(nproc)" --target aprt aprt_engine aprt_kernels aprt_base 2>&1 |
  { grep -E "warning:|error:" || true; }
[ -x "$build/bin/aprt" ] || fail "$build/bin/aprt was not built"

echo "== cmake --install (DESTDIR) against the packages' file list"
root=$PWD/$build/install-root
DESTDIR="$root" cmake --install "$build" >/dev/null
(cd "$build" && cpack -G DEB >/dev/null) || fail "cpack failed (see $build/_CPack_Packages)"
installed=$(cd "$root" && find . -type f -o -type l | sort)
packaged=$(for d in "$build"/aprt*.deb; do dpkg-deb -c "$d"; done | awk '$1 !~ /^d/ {print $6}' | sort)
if [ "$installed" != "$packaged" ]; then
  diff <(echo "$packaged") <(echo "$installed") | head -20 >&2
  fail "cmake --install and the packages differ (< package, > install)"
fi
echo "   $(wc -l <<<"$installed") files, the same in both"

echo "== the installed aprt"
aprt=$root/usr/bin/aprt
"$aprt" run --check --config "$root/etc/aprt/aprt.yaml" --model "$root/usr/share/aprt/model_bin/town_64.aprt"
"$aprt" run --frames 10 --quiet | tail -3
echo "== plain $compiler $type build: ok"
