# ARMv5TE, soft-float, no divide instruction: the PDA class (XScale-like),
# with Debian's cross compiler (g++-arm-linux-gnueabi) and
# qemu-user (qemu-arm) running test binaries through CMAKE_CROSSCOMPILING_EMULATOR.
#   cmake -S . -B build/arm-linux-gnueabi -G Ninja -DCMAKE_TOOLCHAIN_FILE=toolchains/arm-linux-gnueabi.cmake
# A cross build is handheld-only (STIPPLE_HANDHELD_ONLY): core, raster and their tests.
set(CMAKE_SYSTEM_NAME Linux)
set(CMAKE_SYSTEM_PROCESSOR arm)
set(CMAKE_CXX_COMPILER arm-linux-gnueabi-g++)
set(CMAKE_C_COMPILER arm-linux-gnueabi-gcc)
set(CMAKE_CXX_FLAGS_INIT "-march=armv5te -mfloat-abi=soft -marm")
set(CMAKE_C_FLAGS_INIT "-march=armv5te -mfloat-abi=soft -marm")
set(CMAKE_CROSSCOMPILING_EMULATOR qemu-arm -L /usr/arm-linux-gnueabi)
set(CMAKE_FIND_ROOT_PATH /usr/arm-linux-gnueabi)
set(CMAKE_FIND_ROOT_PATH_MODE_PROGRAM NEVER)
set(CMAKE_FIND_ROOT_PATH_MODE_LIBRARY ONLY)
set(CMAKE_FIND_ROOT_PATH_MODE_INCLUDE ONLY)
set(CMAKE_FIND_ROOT_PATH_MODE_PACKAGE ONLY)
