# 64-bit Arm Linux boards (Raspberry Pi 4/5, i.MX8, RK35xx) on Debian's arm64 cross compiler; tests run under
# qemu-aarch64. scripts/cross-build arm64 makes the sysroot.
set(CMAKE_SYSTEM_PROCESSOR aarch64)
set(LEVER_CROSS_TRIPLET aarch64-linux-gnu)
set(LEVER_CROSS_QEMU qemu-aarch64)
include(${CMAKE_CURRENT_LIST_DIR}/debian-sysroot-cross.cmake)
