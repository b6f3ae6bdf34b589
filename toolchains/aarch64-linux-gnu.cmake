# Cross build for 64-bit ARM Linux ECUs (Cortex-A72/A76 class) with Debian's
# g++-aarch64-linux-gnu. Target binaries run on the build host through
# qemu-user (ctest and gtest discovery use CMAKE_CROSSCOMPILING_EMULATOR).
# Baseline armv8-a: no instruction beyond it is emitted outside the kernels
# that check the CPU first (see docs/architecture.md, "Dispatch").
set(CMAKE_SYSTEM_NAME Linux)
set(CMAKE_SYSTEM_PROCESSOR aarch64)
set(CMAKE_C_COMPILER aarch64-linux-gnu-gcc)
set(CMAKE_CXX_COMPILER aarch64-linux-gnu-g++)
set(CMAKE_C_FLAGS_INIT "-march=armv8-a")
set(CMAKE_CXX_FLAGS_INIT "-march=armv8-a")
set(CMAKE_FIND_ROOT_PATH /usr/aarch64-linux-gnu)
set(CMAKE_FIND_ROOT_PATH_MODE_PROGRAM NEVER)
set(CMAKE_FIND_ROOT_PATH_MODE_LIBRARY ONLY)
set(CMAKE_FIND_ROOT_PATH_MODE_INCLUDE ONLY)
set(CMAKE_FIND_ROOT_PATH_MODE_PACKAGE ONLY)
set(CMAKE_CROSSCOMPILING_EMULATOR qemu-aarch64 -L /usr/aarch64-linux-gnu)

# Target libraries unpacked by tools/aarch64_sysroot.sh (libyaml, libpng, libjpeg, zlib; static).
set(APRT_AARCH64_SYSROOT "${CMAKE_CURRENT_LIST_DIR}/../build/sysroot-aarch64" CACHE PATH
    "Unpacked arm64 .debs for the cross build")
list(APPEND CMAKE_FIND_ROOT_PATH ${APRT_AARCH64_SYSROOT})
set(ENV{PKG_CONFIG_LIBDIR} "${APRT_AARCH64_SYSROOT}/usr/lib/aarch64-linux-gnu/pkgconfig")
set(ENV{PKG_CONFIG_SYSROOT_DIR} "${APRT_AARCH64_SYSROOT}")
# Debian's multiarch headers (jconfig.h) live in usr/include/aarch64-linux-gnu.
set(CMAKE_C_STANDARD_INCLUDE_DIRECTORIES ${APRT_AARCH64_SYSROOT}/usr/include/aarch64-linux-gnu)
set(CMAKE_CXX_STANDARD_INCLUDE_DIRECTORIES ${APRT_AARCH64_SYSROOT}/usr/include/aarch64-linux-gnu)
