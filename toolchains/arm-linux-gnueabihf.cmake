# ARMv7-A, hard-float, NEON.
# Packages: g++-arm-linux-gnueabihf qemu-user.
#   cmake -S . -B build/armv7 -G Ninja -DCMAKE_TOOLCHAIN_FILE=toolchains/arm-linux-gnueabihf.cmake
set(cross_triple arm-linux-gnueabihf)
set(cross_processor arm)
set(cross_qemu qemu-arm)
set(cross_flags "-march=armv7-a -mfloat-abi=hard -mfpu=neon -Wno-psabi")  # see arm-linux-gnueabi.cmake
include(${CMAKE_CURRENT_LIST_DIR}/debian-cross.cmake)
