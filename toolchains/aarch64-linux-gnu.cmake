# AArch64 (ARMv8-A).
# Packages: g++-aarch64-linux-gnu qemu-user.
#   cmake -S . -B build/aarch64 -G Ninja -DCMAKE_TOOLCHAIN_FILE=toolchains/aarch64-linux-gnu.cmake
set(cross_triple aarch64-linux-gnu)
set(cross_processor aarch64)
set(cross_qemu qemu-aarch64)
set(cross_flags "")
include(${CMAKE_CURRENT_LIST_DIR}/debian-cross.cmake)
