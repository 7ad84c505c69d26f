# Shared by the Debian cross toolchain files: Debian's cross compilers (crossbuild-essential-<arch>) against a
# sysroot of the target's Debian packages (scripts/sysroot), named by LEVER_SYSROOT (scripts/cross-build passes
# -DLEVER_SYSROOT=$(scripts/sysroot ARCH)). The including file sets CMAKE_SYSTEM_PROCESSOR, LEVER_CROSS_TRIPLET and
# LEVER_CROSS_QEMU.
set(CMAKE_SYSTEM_NAME Linux)
set(CMAKE_C_COMPILER ${LEVER_CROSS_TRIPLET}-gcc)
set(CMAKE_CXX_COMPILER ${LEVER_CROSS_TRIPLET}-g++)

# try_compile re-reads this file in a project of its own, which gets LEVER_SYSROOT only through this list.
list(APPEND CMAKE_TRY_COMPILE_PLATFORM_VARIABLES LEVER_SYSROOT)
if(NOT IS_DIRECTORY "${LEVER_SYSROOT}/usr/lib/${LEVER_CROSS_TRIPLET}")
  message(FATAL_ERROR "no ${LEVER_CROSS_TRIPLET} sysroot at '${LEVER_SYSROOT}': configure with "
                      "-DLEVER_SYSROOT=$(scripts/sysroot ARCH), or build with scripts/cross-build ARCH")
endif()
set(CMAKE_SYSROOT ${LEVER_SYSROOT})
# The compiler's own C++ headers and libstdc++/libgcc come with the cross toolchain; every other header, library,
# <Pkg>Config.cmake and .pc file comes from the sysroot alone, so nothing of the build machine's own packages can
# slip into a target binary. Debian puts the target's libraries under lib/<triplet>.
set(CMAKE_LIBRARY_ARCHITECTURE ${LEVER_CROSS_TRIPLET})
set(CMAKE_FIND_ROOT_PATH_MODE_PROGRAM NEVER)
set(CMAKE_FIND_ROOT_PATH_MODE_LIBRARY ONLY)
set(CMAKE_FIND_ROOT_PATH_MODE_INCLUDE ONLY)
set(CMAKE_FIND_ROOT_PATH_MODE_PACKAGE ONLY)
# pkg-config reads only the sysroot's .pc files and prefixes their paths with it (Debian 12 ships no
# <triplet>-pkg-config wrapper that would).
set(ENV{PKG_CONFIG_SYSROOT_DIR} ${LEVER_SYSROOT})
set(ENV{PKG_CONFIG_LIBDIR} "${LEVER_SYSROOT}/usr/lib/${LEVER_CROSS_TRIPLET}/pkgconfig:${LEVER_SYSROOT}/usr/share/pkgconfig")
set(ENV{PKG_CONFIG_PATH} "")

# Test programs run under qemu-user (no binfmt_misc needed) on the sysroot's own dynamic loader and libc, a
# matching pair. Not the cross toolchain's glibc (libc6-<arch>-cross, another build): its loader with a libc.so.6
# of another build hangs in pthread_create.
find_program(LEVER_CROSS_QEMU_PROGRAM NAMES ${LEVER_CROSS_QEMU}-static ${LEVER_CROSS_QEMU})
if(LEVER_CROSS_QEMU_PROGRAM)
  set(CMAKE_CROSSCOMPILING_EMULATOR ${LEVER_CROSS_QEMU_PROGRAM} -L ${LEVER_SYSROOT})
endif()
