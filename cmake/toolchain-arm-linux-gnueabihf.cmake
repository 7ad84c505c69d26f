# 32-bit Arm Linux boards with a hardware FPU (Debian armhf: ARMv7-A, VFPv3-D16, Thumb-2; BeagleBone, i.MX6,
# STM32MP1) on Debian's armhf cross compiler. scripts/cross-build armhf makes the sysroot.
set(CMAKE_SYSTEM_PROCESSOR arm)
set(LEVER_CROSS_TRIPLET arm-linux-gnueabihf)
set(LEVER_CROSS_QEMU qemu-arm)
include(${CMAKE_CURRENT_LIST_DIR}/debian-sysroot-cross.cmake)
# GCC notes that the passing of some std::vector and std::map iterators changed in GCC 7.1 (-Wpsabi): it matters
# only when linking against code built by GCC 6 or older, which nothing in a bookworm sysroot is. It is a note,
# not a warning, but hundreds of them bury the real diagnostics.
string(APPEND CMAKE_CXX_FLAGS_INIT " -Wno-psabi")
