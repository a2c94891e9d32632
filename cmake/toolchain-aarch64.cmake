# Cross-compiling rilbed's vision module for 64-bit ARM (aarch64) on a Debian 12 amd64 host,
# and running what it builds under qemu: `./run arm` (with RILBED_VISION_ONLY=ON, in build-arm/).
#
#   cmake -S . -B build-arm -DCMAKE_TOOLCHAIN_FILE=cmake/toolchain-aarch64.cmake \
#         -DRILBED_ARM_SYSROOT=$PWD/build-arm-sysroot -DRILBED_VISION_ONLY=ON
#
# The compilers are Debian's cross compilers (crossbuild-essential-arm64): their own C and
# C++ runtime (/usr/aarch64-linux-gnu) comes first. Every other library comes from the
# sysroot RILBED_ARM_SYSROOT, Debian's arm64 packages unpacked there by `./run arm`
# (not installed through multiarch: several of them, libyaml-cpp-dev and libgdal32 under
# OpenCV's libraries among them, are not Multi-Arch: same, so dpkg would remove the host's
# own to install them). What is built runs under qemu-aarch64-static with that sysroot as
# its root for libraries (-L): CTest's tests, and gtest_discover_tests' listing of them.
set(CMAKE_SYSTEM_NAME Linux)
set(CMAKE_SYSTEM_PROCESSOR aarch64)
set(CMAKE_C_COMPILER aarch64-linux-gnu-gcc)
set(CMAKE_CXX_COMPILER aarch64-linux-gnu-g++)
set(CMAKE_LIBRARY_ARCHITECTURE aarch64-linux-gnu)

# The sysroot: a -D on the first configure, else $RILBED_ARM_SYSROOT, else build-arm-sysroot/
# beside this repository's build folders. try_compile projects get it through
# CMAKE_TRY_COMPILE_PLATFORM_VARIABLES.
if(NOT RILBED_ARM_SYSROOT)
  if(DEFINED ENV{RILBED_ARM_SYSROOT})
    set(RILBED_ARM_SYSROOT "$ENV{RILBED_ARM_SYSROOT}")
  else()
    get_filename_component(RILBED_ARM_SYSROOT "${CMAKE_CURRENT_LIST_DIR}/../build-arm-sysroot" ABSOLUTE)
  endif()
endif()
set(RILBED_ARM_SYSROOT "${RILBED_ARM_SYSROOT}" CACHE PATH "arm64 sysroot (Debian's arm64 packages unpacked)")
list(APPEND CMAKE_TRY_COMPILE_PLATFORM_VARIABLES RILBED_ARM_SYSROOT)
if(NOT EXISTS "${RILBED_ARM_SYSROOT}/usr/lib/aarch64-linux-gnu")
  message(FATAL_ERROR "no arm64 sysroot at ${RILBED_ARM_SYSROOT}: `./run arm` makes it")
endif()
set(CMAKE_SYSROOT "${RILBED_ARM_SYSROOT}")

# Headers, libraries and packages from the cross toolchain's root and the sysroot only (never
# the host's x86-64 ones); programs (pkg-config, lcm-gen...) from the host.
set(CMAKE_FIND_ROOT_PATH /usr/aarch64-linux-gnu "${RILBED_ARM_SYSROOT}")
set(CMAKE_FIND_ROOT_PATH_MODE_PROGRAM NEVER)
set(CMAKE_FIND_ROOT_PATH_MODE_LIBRARY ONLY)
set(CMAKE_FIND_ROOT_PATH_MODE_INCLUDE ONLY)
set(CMAKE_FIND_ROOT_PATH_MODE_PACKAGE ONLY)

# pkg-config (Cairo, AprilTag) reads the sysroot's arm64 .pc files only and prefixes their
# paths with the sysroot.
set(ENV{PKG_CONFIG_DIR} "")
set(ENV{PKG_CONFIG_PATH} "")
set(ENV{PKG_CONFIG_LIBDIR}
    "${RILBED_ARM_SYSROOT}/usr/lib/aarch64-linux-gnu/pkgconfig:${RILBED_ARM_SYSROOT}/usr/share/pkgconfig")
set(ENV{PKG_CONFIG_SYSROOT_DIR} "${RILBED_ARM_SYSROOT}")

# aarch64 programs run under qemu, with the sysroot's loader and libraries.
find_program(RILBED_QEMU_AARCH64 NAMES qemu-aarch64-static qemu-aarch64 REQUIRED)
set(CMAKE_CROSSCOMPILING_EMULATOR "${RILBED_QEMU_AARCH64};-L;${RILBED_ARM_SYSROOT}")
