#!/usr/bin/env bash
# Builds vimc.ko -- the virtual camera pipeline libcamera's own CI drives
# (sensor -> debayer -> scaler -> capture, with a media controller graph) --
# for the HIL rig's kernel, which Debian builds without it
# (CONFIG_VIDEO_VIMC is not set): the module source from Debian's
# linux-source-6.1 (downloaded, only drivers/media/test-drivers/vimc
# unpacked), built out of tree against linux-headers-<the rig's version>
# (installed: the headers, linux-kbuild and the compiler Debian's kernel was
# built with). Also udevadm from Debian's udev package (downloaded, never
# installed): the VM runs udevd, so libcamera sees devices initialised and
# hears of hot-unplug and hot-plug as on a vehicle. Cached beside the kernel;
# prints the path of vimc.ko (udevadm beside it).
# Exit 3 with the reason when the packages cannot be had (no apt source):
# the scenario then skips, saying why.
#   tests/hil/vimc.sh KERNEL_DIR   (what tests/hil/kernel.sh printed)
set -euo pipefail
kdir="${1:?usage: vimc.sh KERNEL_DIR}"
kver=$(cat "$kdir/version")
out="$kdir/vimc"
exec 9>"$kdir/.vimc.lock"
flock 9
if [ -f "$out/vimc.ko" ] && [ -x "$out/udevadm" ]; then echo "$out/vimc.ko"; exit 0; fi
skip() { echo "vimc: $*" >&2; exit 3; }
headers="/usr/src/linux-headers-$kver"
if [ ! -f "$headers/Makefile" ]; then
  SUDO=""; [ "$(id -u)" -ne 0 ] && SUDO="sudo"
  DEBIAN_FRONTEND=noninteractive $SUDO apt-get install -y -qq --no-install-recommends \
    "linux-headers-$kver" >/dev/null 2>&1 || skip "cannot install linux-headers-$kver (apt source unreachable?)"
fi
src=$(mktemp -d)
trap 'rm -rf "$src"' EXIT
# The source package matching the running ABI: linux-source-6.1 of the same upload.
srcver=$(dpkg-query -W -f='${Version}' "linux-headers-$kver" 2>/dev/null || true)
(cd "$src" && apt-get download -q "linux-source-6.1=$srcver" >/dev/null 2>&1) ||
  (cd "$src" && apt-get download -q linux-source-6.1 >/dev/null 2>&1) ||
  skip "cannot download linux-source-6.1 (apt source unreachable?)"
dpkg-deb --fsys-tarfile "$src"/linux-source-6.1_*.deb |
  tar -x -O ./usr/src/linux-source-6.1.tar.xz |
  tar -xJ -C "$src" linux-source-6.1/drivers/media/test-drivers/vimc
rm -f "$src"/linux-source-6.1_*.deb
m="$src/linux-source-6.1/drivers/media/test-drivers/vimc"
make -s -C "$headers" M="$m" CONFIG_VIDEO_VIMC=m modules >"$src/build.log" 2>&1 ||
  { cat "$src/build.log" >&2; echo "vimc: the module did not build" >&2; exit 1; }
(cd "$src" && apt-get download -q udev >/dev/null 2>&1) || skip "cannot download udev (apt source unreachable?)"
dpkg -x "$src"/udev_*.deb "$src/udev"
mkdir -p "$out"
cp "$src/udev/bin/udevadm" "$out/udevadm"
cp "$m/vimc.ko" "$out/vimc.ko"
echo "$out/vimc.ko"
