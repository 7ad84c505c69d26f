# 32-bit Arm Linux boards with a hardware FPU (Debian armhf: ARMv7-A, VFPv3-D16, Thumb-2; BeagleBone, i.MX6,
# STM32MP1) on Debian's armhf cross compiler. scripts/cross-build armhf makes the sysroot.
set(CMAKE_SYSTEM_PROCESSOR arm)
set(LEVER_CROSS_TRIPLET arm-linux-gnueabihf)
set(LEVER_CROSS_QEMU qemu-arm)
include(${CMAKE_CURRENT_LIST_DIR}/debian-sysroot-cross.cmake)
