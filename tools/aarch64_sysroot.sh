#!/usr/bin/env bash
# Target libraries for the aarch64 cross build, kept out of the system: the
# arm64 .debs are downloaded (never installed -- installing arm64 packages
# side by side would pull libc6:arm64 and upgrade host packages) and unpacked
# into build/sysroot-aarch64, which toolchains/aarch64-linux-gnu.cmake
# searches. Static archives only, so the test binaries run under qemu-aarch64
# without extra shared libraries. Idempotent.
set -euo pipefail
cd "$(dirname "$0")/.."
root="$PWD/build/sysroot-aarch64"
packages=(libyaml-0-2:arm64 libyaml-dev:arm64 libpng16-16:arm64 libpng-dev:arm64 zlib1g:arm64
          zlib1g-dev:arm64 libjpeg62-turbo:arm64 libjpeg62-turbo-dev:arm64 libsodium23:arm64
          libsodium-dev:arm64)
# Ready when unpacked from this very package list (a changed list rebuilds it).
[ "$(cat "$root/.ready" 2>/dev/null)" = "${packages[*]}" ] && exit 0
SUDO=""
if [ "$(id -u)" -ne 0 ]; then SUDO="sudo"; fi
if ! dpkg --print-foreign-architectures | grep -qx arm64; then
  echo "aarch64 sysroot: adding the arm64 architecture to apt (downloads only)"
  $SUDO dpkg --add-architecture arm64
  $SUDO apt-get update -qq
fi
rm -rf "$root" && mkdir -p "$root/debs"
(cd "$root/debs" && apt-get download -q "${packages[@]}" >/dev/null 2>&1) || {
  $SUDO apt-get update -qq
  (cd "$root/debs" && apt-get download -q "${packages[@]}" >/dev/null 2>&1)
} || { echo "aarch64 sysroot: apt-get download ${packages[*]} failed" >&2; exit 1; }
for d in "$root"/debs/*.deb; do dpkg -x "$d" "$root"; done
# Static linking: drop the shared objects so the linker takes the .a archives.
find "$root/usr/lib/aarch64-linux-gnu" "$root/lib" -name '*.so*' -delete 2>/dev/null || true
rm -rf "$root/debs"
echo "${packages[*]}" >"$root/.ready"
echo "aarch64 sysroot: $root"
