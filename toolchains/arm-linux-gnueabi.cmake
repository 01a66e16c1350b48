# ARMv5TE, soft-float, no divide instruction: the PDA class (XScale-like).
# Packages: g++-arm-linux-gnueabi qemu-user.   cmake --preset armv5
set(cross_triple arm-linux-gnueabi)
set(cross_processor arm)
set(cross_qemu qemu-arm)
# -Wno-psabi: GCC notes that std::vector<double> iterators pass differently
# since GCC 7.1; everything here is built by one compiler.
set(cross_flags "-march=armv5te -mfloat-abi=soft -marm -Wno-psabi")
include(${CMAKE_CURRENT_LIST_DIR}/debian-cross.cmake)
