# ARMv5TE, soft-float, no divide instruction: the PDA class (XScale-like).
# Packages: g++-arm-linux-gnueabi qemu-user.   cmake --preset armv5
set(cross_triple arm-linux-gnueabi)
set(cross_processor arm)
set(cross_qemu qemu-arm)
set(cross_flags "-march=armv5te -mfloat-abi=soft -marm")
include(${CMAKE_CURRENT_LIST_DIR}/debian-cross.cmake)
