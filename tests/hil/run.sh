#!/usr/bin/env bash
# The HIL rig: boots Debian's kernel under qemu with real SocketCAN (vcan) and
# a watchdog (softdog), runs one scenario per boot inside it, and reports TAP.
#
#   tests/hil/run.sh [--build DIR] [--out DIR] SCENARIO...     (default: all)
#
# SCENARIO is a file tests/hil/scenarios/NAME.sh; it runs under busybox sh in
# the VM with aprt (the release build), can-utils, iproute2, a tiny model and
# a short synthetic drive, and reports with ok/not_ok (scenarios/lib.sh).
# A scenario may have a host-side part, scenarios/NAME.host, run after its VM
# on what the VM reported (e.g. a frame to recompute here).
# Results: OUT/NAME.tap, OUT/NAME.console.log. Exit status 0 only if every
# scenario's plan completed and every test passed.
set -euo pipefail
here="$(cd "$(dirname "$0")" && pwd)"
top="$(cd "$here/../.." && pwd)"
build="$top/build/release"
out="$top/build/hil"
while [ $# -gt 0 ]; do
  case "$1" in
    --build) build="$2"; shift 2 ;;
    --out) out="$2"; shift 2 ;;
    -h|--help) sed -n 2,15p "$0"; exit 0 ;;
    *) break ;;
  esac
done
scenarios=("$@")
if [ ${#scenarios[@]} -eq 0 ]; then
  for f in "$here"/scenarios/*.sh; do
    n=$(basename "$f" .sh); [ "$n" = lib ] || scenarios+=("$n")
  done
fi
fail() { echo "hil: $*" >&2; exit 1; }
for tool in qemu-system-x86_64 cpio busybox; do
  command -v "$tool" >/dev/null || fail "$tool not found (tools/setup.sh installs qemu-system-x86 cpio busybox-static)"
done
[ -x "$build/bin/aprt" ] || fail "no $build/bin/aprt (build the release preset first)"
[ -x "$build/bin/aprt_synth" ] || fail "no $build/bin/aprt_synth"

kdir=$("$here/kernel.sh")
kver=$(cat "$kdir/version")
mkdir -p "$out"
work=$(mktemp -d "$out/.work.XXXXXX")
trap 'rm -rf "$work"' EXIT

# --- the payload: aprt, peers, data --------------------------------------------
root="$work/root"
mkdir -p "$root"/{bin,sbin,usr/bin,lib,lib64,proc,sys,dev,tmp,etc,hil,aprt/bin,aprt/config,aprt/data}
cp /usr/bin/busybox "$root/bin/busybox"
copy_with_libs() {  # binary, destination folder in the VM
  cp "$1" "$root$2/"
  ldd "$1" | awk '/=>/ {print $3} $1 ~ /^\/lib64\// {print $1}' | while read -r lib; do
    [ -f "$lib" ] || continue
    mkdir -p "$root$(dirname "$lib")"
    cp -L "$lib" "$root$lib"
  done
}
copy_with_libs "$build/bin/aprt" /aprt/bin
# The DDS endpoints' module (Cyclone DDS and its libraries come with it).
if [ -f "$build/lib/aprt/aprt_dds.so" ]; then
  mkdir -p "$root/aprt/lib/aprt"
  copy_with_libs "$build/lib/aprt/aprt_dds.so" /aprt/lib/aprt
fi
# libcamera (camera_vimc): aprt's module, libcamera's vimc IPA with its proxy
# and data, each with its libraries.
if [ -f "$build/lib/aprt/aprt_libcamera.so" ]; then
  mkdir -p "$root/aprt/lib/aprt"
  copy_with_libs "$build/lib/aprt/aprt_libcamera.so" /aprt/lib/aprt
  lcdir=/usr/lib/x86_64-linux-gnu/libcamera
  if [ -f "$lcdir/ipa_vimc.so" ]; then
    mkdir -p "$root$lcdir" "$root/usr/share/libcamera/ipa"
    copy_with_libs "$lcdir/ipa_vimc.so" "$lcdir"
    cp "$lcdir/ipa_vimc.so.sign" "$root$lcdir/" 2>/dev/null || true
    copy_with_libs "$lcdir/vimc_ipa_proxy" "$lcdir"
    cp -r /usr/share/libcamera/ipa/vimc "$root/usr/share/libcamera/ipa/"
  fi
fi
for t in candump cansend; do copy_with_libs "/usr/bin/$t" /usr/bin; done
copy_with_libs "$(command -v ip)" /usr/bin
cp "$top/config/aprt_pose.dbc" "$top/config/vehicle_odometry_example.dbc" "$root/aprt/config/"
cp "$here"/scenarios/*.sh "$here"/scenarios/*.yaml "$root/hil/" 2>/dev/null || true

# A tiny model (untrained weights) and a short drive: the CAN path is what is under test.
data="$out/data"
if [ ! -f "$data/model.aprt" ] || [ ! -f "$data/drive/poses.txt" ]; then
  mkdir -p "$data"
  PYTHONPATH="$top/tools" PYTHONWARNINGS=ignore /usr/bin/python3 -m aprt_tools golden --config tiny \
    --convert --out "$data/tiny" >/dev/null
  cp "$data/tiny/model.aprt" "$data/model.aprt"
  "$build/bin/aprt_synth" --out "$data/drive" --frames 30 --split test --width 128 --height 96 >/dev/null
fi
cp "$data/model.aprt" "$root/aprt/data/"
# The shipped model, for the scenarios that check real poses (camera_dds).
[ -f "$top/model_bin/town_64.aprt" ] && cp "$top/model_bin/town_64.aprt" "$root/aprt/data/shipped.aprt"
cp -r "$data/drive" "$root/aprt/data/drive"

# Modules and what they depend on, from modules.dep.
mods="can can_raw can_dev vcan softdog vivid"   # vivid is loaded by the camera scenarios
load="can can_raw can_dev vcan softdog"
mroot="$kdir/root/lib/modules/$kver"
mkdir -p "$root/lib/modules/$kver"
cp "$mroot"/modules.{dep,alias,builtin,order} "$root/lib/modules/$kver/" 2>/dev/null || true
copy_module() {  # a module of the kernel and what it depends on, from modules.dep
  local line
  line=$(grep -E "/${1//[-_]/[-_]}\.ko(\.xz)?:" "$mroot/modules.dep" || true)
  [ -n "$line" ] || fail "module $1 not in $kver's modules.dep"
  for f in ${line/:/ }; do
    mkdir -p "$root/lib/modules/$kver/$(dirname "$f")"
    cp "$mroot/$f" "$root/lib/modules/$kver/$f"
  done
}
for m in $mods; do copy_module "$m"; done
echo "$load" > "$root/etc/hil-modules"
# vimc, built for this kernel (tests/hil/vimc.sh), with the modules it needs;
# the camera_vimc scenario loads it, or skips with the reason it is missing.
if vimc=$("$here/vimc.sh" "$kdir" 2>"$work/vimc.err"); then
  mkdir -p "$root/lib/modules/$kver/extra"
  cp "$vimc" "$root/lib/modules/$kver/extra/vimc.ko"
  deps=$(strings "$vimc" | sed -n 's/^depends=//p' | tr ',' ' ')
  for m in $deps; do copy_module "$m"; done
  echo "$deps" > "$root/etc/hil-vimc-deps"
  # udevd (udevadm under its daemon's name): libcamera takes only devices
  # udev initialised and learns of unplugs from udev's events.
  copy_with_libs "$(dirname "$vimc")/udevadm" /usr/bin
  mkdir -p "$root/lib/systemd"
  ln -sf /usr/bin/udevadm "$root/lib/systemd/systemd-udevd"
else
  { echo "vimc.ko could not be built for $kver:"; cat "$work/vimc.err"; } | tr '\n' ' ' > "$root/hil/vimc-skip"
fi

cat > "$root/init" <<'INIT'
#!/bin/busybox sh
/bin/busybox --install -s /bin
mount -t proc proc /proc
mount -t sysfs sys /sys
mount -t devtmpfs dev /dev
mount -t tmpfs tmp /tmp
export PATH=/usr/bin:/bin:/sbin APRT_DATA_DIR=/aprt HOME=/tmp
for m in $(cat /etc/hil-modules); do modprobe "$m" || echo "hil: modprobe $m failed"; done
ip link set lo up
scenario=$(sed -n 's/.*hil.scenario=\([^ ]*\).*/\1/p' /proc/cmdline)
cd /hil
sh "/hil/$scenario.sh" > /dev/ttyS1 2>&1
echo "hil-exit $?" > /dev/ttyS2
poweroff -f
INIT
chmod +x "$root/init"
(cd "$root" && find . | cpio -o -H newc --quiet) > "$work/initrd.cpio"

# --- boot one VM per scenario ----------------------------------------------------
accel="tcg"
if [ -w /dev/kvm ] && [ "${APRT_HIL_KVM:-0}" = 1 ]; then accel="kvm"; fi  # opt in: nested KVM here cannot boot it
status=0
for s in "${scenarios[@]}"; do
  [ -f "$here/scenarios/$s.sh" ] || fail "no scenario '$s' (tests/hil/scenarios/$s.sh)"
  tap="$out/$s.tap"; console="$out/$s.console.log"; exitf="$work/$s.exit"
  : > "$tap"; : > "$exitf"
  start=$(date +%s.%N)
  timeout "${APRT_HIL_TIMEOUT:-180}" qemu-system-x86_64 -accel "$accel" -cpu max -m 1024 -smp 2 \
    -kernel "$kdir/vmlinux" -initrd "$work/initrd.cpio" \
    -append "console=ttyS0 panic=-1 oops=panic quiet hil.scenario=$s" \
    -display none -no-reboot -monitor none \
    -serial "file:$console" -serial "file:$tap" -serial "file:$exitf" \
    || true
  took=$(awk -v a="$start" -v b="$(date +%s.%N)" 'BEGIN {print b - a}')
  # The scenario may expect the VM to be reset (watchdog): it says so in its TAP plan.
  code=$(sed -n 's/^hil-exit \([0-9]*\).*/\1/p' "$exitf" | tr -d '\r')
  expect_reset=$(grep -c '^# expect: reset' "$tap" || true)
  if [ "$expect_reset" -gt 0 ]; then
    if [ -z "$code" ]; then echo "ok - $s: the VM was reset (no exit status)" >> "$tap"
    else echo "not ok - $s: expected a reset, the scenario exited $code" >> "$tap"; fi
  elif [ -z "$code" ]; then
    echo "not ok - $s: the VM stopped without an exit status (reset, panic or timeout)" >> "$tap"
  fi
  # Host-side checks of what the VM produced (scenarios/NAME.host: bash, appends TAP).
  if [ -f "$here/scenarios/$s.host" ]; then
    bash "$here/scenarios/$s.host" "$tap" "$build" "$top" "$work" >> "$tap" 2>&1 ||
      echo "not ok - $s: host-side check failed to run" >> "$tap"
  fi
  fails=$(grep -c '^not ok' "$tap" || true); oks=$(grep -c '^ok' "$tap" || true)
  printf 'hil: %-20s %d ok, %d not ok, %.1f s (%s)\n' "$s" "$oks" "$fails" "$took" "$accel"
  if [ "$fails" -gt 0 ] || [ "$oks" -eq 0 ] || { [ -n "$code" ] && [ "$code" != 0 ]; }; then
    status=1
    grep '^not ok' "$tap" | sed 's/^/    /' || true
    echo "    logs: $tap, $console"
  fi
done
exit $status
