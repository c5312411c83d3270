# Toolchain file: cross-compiles liod for arm64 (aarch64, the Jetson Orin) on an x86-64 Debian or
# Ubuntu host with Debian's cross compiler (crossbuild-essential-arm64: aarch64-linux-gnu-gcc/g++)
# against an arm64 sysroot that holds the arm64 -dev packages (scripts/arm64.sh makes one with
# mmdebstrap). A sysroot rather than multiarch :arm64 packages on the host, because several -dev
# packages liod needs (PCL's, Boost's, VTK's) are not Multi-Arch: same, and apt would remove the
# host's amd64 ones to install them.
#
#   cmake -S . -B build-arm64 -DCMAKE_TOOLCHAIN_FILE=cmake/aarch64-linux-gnu.cmake \
#         -DLIOD_ARM64_SYSROOT=/path/to/arm64-root
#
# The tests and tools then run under qemu-user (CMAKE_CROSSCOMPILING_EMULATOR), so `ctest` in the
# tree runs the arm64 test programs on the host.

set(CMAKE_SYSTEM_NAME Linux)
set(CMAKE_SYSTEM_PROCESSOR aarch64)

# The sysroot is a cache entry, and try_compile's inner projects receive it too (they re-read
# this file without the cache).
set(LIOD_ARM64_SYSROOT "$ENV{LIOD_ARM64_SYSROOT}" CACHE PATH "arm64 sysroot with liod's -dev packages")
list(APPEND CMAKE_TRY_COMPILE_PLATFORM_VARIABLES LIOD_ARM64_SYSROOT)
if(NOT LIOD_ARM64_SYSROOT OR NOT EXISTS "${LIOD_ARM64_SYSROOT}/usr/include")
  message(FATAL_ERROR "LIOD_ARM64_SYSROOT ('${LIOD_ARM64_SYSROOT}') is not an arm64 sysroot; "
                      "scripts/arm64.sh makes one")
endif()

set(CMAKE_C_COMPILER aarch64-linux-gnu-gcc)
set(CMAKE_CXX_COMPILER aarch64-linux-gnu-g++)
set(CMAKE_SYSROOT "${LIOD_ARM64_SYSROOT}")
set(CMAKE_LIBRARY_ARCHITECTURE aarch64-linux-gnu)

# Libraries, headers and CMake packages only from the sysroot; programs (pkg-config, dpkg-shlibdeps,
# python3) from the host.
set(CMAKE_FIND_ROOT_PATH "${LIOD_ARM64_SYSROOT}")
set(CMAKE_FIND_ROOT_PATH_MODE_PROGRAM NEVER)
set(CMAKE_FIND_ROOT_PATH_MODE_LIBRARY ONLY)
set(CMAKE_FIND_ROOT_PATH_MODE_INCLUDE ONLY)
set(CMAKE_FIND_ROOT_PATH_MODE_PACKAGE ONLY)

# pkg-config (libsystemd, libgpiod) reads the sysroot's .pc files and prefixes their paths with it.
set(ENV{PKG_CONFIG_SYSROOT_DIR} "${LIOD_ARM64_SYSROOT}")
set(ENV{PKG_CONFIG_LIBDIR}
    "${LIOD_ARM64_SYSROOT}/usr/lib/aarch64-linux-gnu/pkgconfig:${LIOD_ARM64_SYSROOT}/usr/share/pkgconfig")

# Test programs (and gtest_discover_tests' listing of them) run under qemu-user, the loader and
# shared libraries taken from the sysroot (-L).
find_program(LIOD_QEMU_AARCH64 NAMES qemu-aarch64-static qemu-aarch64)
if(LIOD_QEMU_AARCH64)
  set(CMAKE_CROSSCOMPILING_EMULATOR "${LIOD_QEMU_AARCH64};-L;${LIOD_ARM64_SYSROOT}")
endif()
