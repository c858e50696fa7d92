#!/bin/bash
# install_test.sh BUILD_DIR CONSUMER_SRC WORK_DIR
# Installs the build into a fresh prefix, then builds and runs a consumer of
# liblfio twice: through find_package(lfio) and through pkg-config.
set -eu
build=$1 src=$2 work=$3
rm -rf "$work"
mkdir -p "$work"
prefix=$work/prefix
cmake --install "$build" --prefix "$prefix" > "$work/install.log"
pass=0 fail=0
check() { if "$@"; then pass=$((pass + 1)); else fail=$((fail + 1)); echo "FAILED: $*"; fi; }
libdir=$(find "$prefix" -name 'liblfio.so' -printf '%h\n' | head -1)
check test -x "$prefix/bin/ilf"
check test -f "$prefix/include/lfio/lightfield.h"
check test -f "$libdir/pkgconfig/lfio.pc"
check test -f "$libdir/cmake/lfio/lfioConfig.cmake"
# find_package
cmake -S "$src" -B "$work/cm" -DCMAKE_PREFIX_PATH="$prefix" > "$work/cm.log" 2>&1 || cat "$work/cm.log"
check cmake --build "$work/cm"
check env LD_LIBRARY_PATH="$libdir" "$work/cm/consumer_cmake" "$work/a.h5"
# pkg-config
flags=$(PKG_CONFIG_PATH="$libdir/pkgconfig" pkg-config --cflags --libs lfio)
check cc -std=c99 -o "$work/consumer_pc" "$src/consumer.c" $flags
check env LD_LIBRARY_PATH="$libdir" "$work/consumer_pc" "$work/b.h5"
check env LD_LIBRARY_PATH="$libdir" "$prefix/bin/ilf" --version
echo "$pass passed, $fail failed"
test "$fail" -eq 0
