# Cross-building keel-node for aarch64 boards with Debian's cross toolchain
# (g++-aarch64-linux-gnu) against an arm64 Debian sysroot (docs/cross-build.md).
#
#   cmake --preset aarch64 && cmake --build --preset aarch64     (or: ./keel cross aarch64)
#
# The sysroot is made by tools/make-sysroot-arm64; it is found at KEEL_SYSROOT_AARCH64 (a
# cache variable, or the environment variable of that name), else at
# $KEEL_CACHE/sysroot-arm64, else at .cache/sysroot-arm64 in this checkout.
#
# Programs run at build time come from this machine: idlc, which generates keel-node's DDS
# types, is the host's (Cyclone's idlc_generate looks for it outside the sysroot when cross
# compiling), and must be the sysroot's Cyclone DDS version (the sysroot script checks).
set(CMAKE_SYSTEM_NAME Linux)
set(CMAKE_SYSTEM_PROCESSOR aarch64)
set(CMAKE_LIBRARY_ARCHITECTURE aarch64-linux-gnu)

set(CMAKE_C_COMPILER aarch64-linux-gnu-gcc)
set(CMAKE_CXX_COMPILER aarch64-linux-gnu-g++)

if(NOT KEEL_SYSROOT_AARCH64)
  if(DEFINED ENV{KEEL_SYSROOT_AARCH64} AND NOT "$ENV{KEEL_SYSROOT_AARCH64}" STREQUAL "")
    set(KEEL_SYSROOT_AARCH64 "$ENV{KEEL_SYSROOT_AARCH64}")
  elseif(DEFINED ENV{KEEL_CACHE} AND NOT "$ENV{KEEL_CACHE}" STREQUAL "")
    set(KEEL_SYSROOT_AARCH64 "$ENV{KEEL_CACHE}/sysroot-arm64")
  else()
    get_filename_component(KEEL_SYSROOT_AARCH64 "${CMAKE_CURRENT_LIST_DIR}/../../.cache/sysroot-arm64"
      ABSOLUTE)
  endif()
endif()
set(KEEL_SYSROOT_AARCH64 "${KEEL_SYSROOT_AARCH64}" CACHE PATH "arm64 Debian sysroot (tools/make-sysroot-arm64)")
# try_compile projects read this file again: give them the same sysroot.
list(APPEND CMAKE_TRY_COMPILE_PLATFORM_VARIABLES KEEL_SYSROOT_AARCH64)
if(NOT EXISTS "${KEEL_SYSROOT_AARCH64}/keel-sysroot.txt")
  message(FATAL_ERROR "no arm64 sysroot at ${KEEL_SYSROOT_AARCH64}: make it with "
    "tools/make-sysroot-arm64 (./keel cross aarch64 does that and builds), or point "
    "KEEL_SYSROOT_AARCH64 at one")
endif()

set(CMAKE_SYSROOT "${KEEL_SYSROOT_AARCH64}")
set(CMAKE_FIND_ROOT_PATH "${KEEL_SYSROOT_AARCH64}")
# Libraries, headers and CMake packages from the sysroot only; programs from this machine.
set(CMAKE_FIND_ROOT_PATH_MODE_PROGRAM NEVER)
set(CMAKE_FIND_ROOT_PATH_MODE_LIBRARY ONLY)
set(CMAKE_FIND_ROOT_PATH_MODE_INCLUDE ONLY)
set(CMAKE_FIND_ROOT_PATH_MODE_PACKAGE ONLY)

