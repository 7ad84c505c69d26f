# Shared by the Debian cross toolchain files: Debian's cross compilers (crossbuild-essential-<arch>) with the
# target's libraries installed through multiarch (libfoo-dev:<arch>) into /usr/lib/<triplet> of this same root.
# The including file sets CMAKE_SYSTEM_PROCESSOR, LEVER_CROSS_TRIPLET and LEVER_CROSS_QEMU.
set(CMAKE_SYSTEM_NAME Linux)
set(CMAKE_C_COMPILER ${LEVER_CROSS_TRIPLET}-gcc)
set(CMAKE_CXX_COMPILER ${LEVER_CROSS_TRIPLET}-g++)
# No find root path: multiarch puts the target's files beside the build machine's in /, told apart by the
# triplet in lib/<triplet>, which CMake's searches (libraries, <Pkg>Config.cmake) follow through this variable.
# Header-only, architecture-independent packages (CLI11, nlohmann-json, Catch2's headers) are found in /usr as
# for a native build.
set(CMAKE_LIBRARY_ARCHITECTURE ${LEVER_CROSS_TRIPLET})
# pkg-config must see only the target's .pc files: an amd64 libfoo.pc found for a missing libfoo-dev:<arch> would
# configure, then fail at link time with a less helpful message. Debian 12 ships no <triplet>-pkg-config wrapper.
set(ENV{PKG_CONFIG_LIBDIR} "/usr/lib/${LEVER_CROSS_TRIPLET}/pkgconfig:/usr/share/pkgconfig")
set(ENV{PKG_CONFIG_PATH} "")
# Test programs run under qemu-user (no binfmt_misc needed), in the real root: the multiarch libc6:<arch> that
# the libraries above depend on puts the target's dynamic loader at its usual path, next to the libc it belongs
# to. Not -L /usr/<triplet>: that is the cross toolchain's own glibc (libc6-<arch>-cross, another build), whose
# loader with the multiarch libc.so.6 hangs in pthread_create (2.36-8cross1 against 2.36-9+deb12u14).
find_program(LEVER_CROSS_QEMU_PROGRAM NAMES ${LEVER_CROSS_QEMU}-static ${LEVER_CROSS_QEMU})
if(LEVER_CROSS_QEMU_PROGRAM)
  set(CMAKE_CROSSCOMPILING_EMULATOR ${LEVER_CROSS_QEMU_PROGRAM} -L /)
endif()
