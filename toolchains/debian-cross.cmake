# Shared by the toolchain files: Debian's cross compiler <triple>-g++, its
# sysroot /usr/<triple>, and qemu-user running the target's test binaries
# through CMAKE_CROSSCOMPILING_EMULATOR. The including file sets
# cross_triple, cross_processor, cross_qemu and cross_flags.
# A cross build is handheld-only (STIPPLE_HANDHELD_ONLY): core, raster, the
# handheld program and their tests.
set(CMAKE_SYSTEM_NAME Linux)
set(CMAKE_SYSTEM_PROCESSOR ${cross_processor})
set(CMAKE_CXX_COMPILER ${cross_triple}-g++)
set(CMAKE_C_COMPILER ${cross_triple}-gcc)
set(CMAKE_CXX_FLAGS_INIT "${cross_flags}")
set(CMAKE_C_FLAGS_INIT "${cross_flags}")
set(CMAKE_CROSSCOMPILING_EMULATOR ${cross_qemu} -L /usr/${cross_triple})
set(CMAKE_FIND_ROOT_PATH /usr/${cross_triple})
set(CMAKE_FIND_ROOT_PATH_MODE_PROGRAM NEVER)
set(CMAKE_FIND_ROOT_PATH_MODE_LIBRARY ONLY)
set(CMAKE_FIND_ROOT_PATH_MODE_INCLUDE ONLY)
set(CMAKE_FIND_ROOT_PATH_MODE_PACKAGE ONLY)
