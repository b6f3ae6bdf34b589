#!/usr/bin/env bash
# Fetches Debian's generic amd64 kernel into the HIL cache (never installs it):
# the .deb via `apt-get download`, unpacked with dpkg -x, modules.dep made with
# busybox depmod, and the uncompressed vmlinux extracted from the bzImage's xz
# stream (a PVH boot of vmlinux skips seconds of emulated decompression).
# Prints the cache folder of the kernel. Parallel-safe (flock).
set -euo pipefail
cache="${APRT_HIL_CACHE:-${XDG_CACHE_HOME:-$HOME/.cache}/aprt-hil}"
mkdir -p "$cache"
exec 9>"$cache/.lock"
flock 9

fail() { echo "hil: $*" >&2; exit 1; }
command -v busybox >/dev/null || fail "busybox not found (apt-get install busybox-static)"
command -v xz >/dev/null || fail "xz not found (apt-get install xz-utils)"

# The package linux-image-amd64 depends on today (old ABIs vanish from the mirror).
pkg=$(apt-cache depends linux-image-amd64 2>/dev/null | awk '/Depends: linux-image-[0-9]/ {print $2; exit}')
[ -n "$pkg" ] || fail "cannot resolve linux-image-amd64's kernel package (run apt-get update)"
version=${pkg#linux-image-}
dir="$cache/$pkg"
if [ ! -f "$dir/.ready" ]; then
  rm -rf "$dir" && mkdir -p "$dir/root"
  (cd "$dir" && apt-get download -q "$pkg" >/dev/null 2>&1) || fail "apt-get download $pkg failed"
  dpkg -x "$dir"/*.deb "$dir/root"
  busybox depmod -b "$dir/root" "$version" || fail "depmod failed for $version"
  vmlinuz="$dir/root/boot/vmlinuz-$version"
  [ -f "$vmlinuz" ] || fail "no /boot/vmlinuz-$version in $pkg"
  offset=$(LC_ALL=C grep -abo $'\xfd7zXZ\x00' "$vmlinuz" | head -1 | cut -d: -f1)
  [ -n "$offset" ] || fail "no xz stream in $vmlinuz"
  tail -c +$((offset + 1)) "$vmlinuz" | xz -dc --single-stream > "$dir/vmlinux" 2>/dev/null || true
  [ "$(head -c 4 "$dir/vmlinux" | od -An -tx1 | tr -d ' ')" = "7f454c46" ] ||
    fail "extracting vmlinux from $vmlinuz did not give an ELF file"
  echo "$version" > "$dir/version"
  rm -f "$dir"/*.deb
  touch "$dir/.ready"
fi
echo "$dir"
