#!/bin/bash
# install_test.sh BUILD_DIR CONSUMER_SRC WORK_DIR
# Installs the build into a fresh prefix, then builds and runs a consumer of
# liblfio twice: through find_package(lfio) and through pkg-config. The
# installed ilf does not link OpenImageIO, writes a PNG and an EXR without it,
# and finds the installed image module (LIBDIR/ilfkit/libilfkit_oiio.so) to
# read the EXR back as a probe. Nothing runs with LD_LIBRARY_PATH: the CMake package, lfio.pc's
# rpath and ilf's own rpath must carry the way to the libraries. The manual pages (tools/man_pages.py)
# are installed, one per command, each with every option of its --help, and render without warnings.
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
# Linking must carry the way to the library: every program below runs without LD_LIBRARY_PATH
# (find_package gives the library's full path, pkg-config's lfio.pc an rpath).
unset LD_LIBRARY_PATH
check "$work/cm/consumer_cmake" "$work/a.h5"
# pkg-config
flags=$(PKG_CONFIG_PATH="$libdir/pkgconfig" pkg-config --cflags --libs lfio)
check cc -std=c99 -o "$work/consumer_pc" "$src/consumer.c" $flags
check "$work/consumer_pc" "$work/b.h5"
check "$prefix/bin/ilf" --version
# the image module: installed, loaded by the installed ilf on its first image, never linked
check test -f "$libdir/ilfkit/libilfkit_oiio.so"
check test "$(ldd "$prefix/bin/ilf" | grep -c OpenImageIO)" -eq 0
ilf() { env -u ILFKIT_IMAGE_MODULE "$prefix/bin/ilf" "$@" >>"$work/ilf.log" 2>&1; }
check ilf synth --kind constant --grid 2x2 --n 2 -o "$work/c.h5"
check ilf slice "$work/c.h5" --toward 0,0,1 -o "$work/c.png"
check ilf slice "$work/c.h5" --position 0,0 --layout latlong -o "$work/c.exr"
check test -s "$work/c.png" -a -s "$work/c.exr"
printf '{"plane": {"origin": [0, 0, 0], "u": [1, 0, 0], "v": [0, 1, 0]}, "grid": {"nu": 1, "nv": 1}, "n": 2,
  "pattern": "c.exr"}\n' > "$work/probe.json"
check ilf capture "$work/probe.json" -o "$work/probe.h5" --quiet
check test -s "$work/probe.h5"
# manual pages: one per command of --help, each naming every option its --help lists, and clean roff
mandir=$prefix/share/man/man1
check test -f "$mandir/ilf.1"
commands=$("$prefix/bin/ilf" --help | awk '/^Commands:/ { on = 1; next } /^$/ { on = 0 } on { print $1 }')
check test "$(echo "$commands" | wc -w)" -ge 10
page_has_options() {  # PAGE CMD: every --option of 'ilf CMD --help' is in PAGE (roff's \- read as -)
    local missing=0
    for opt in $("$prefix/bin/ilf" "$2" --help | grep -oE '^ {2,8}(-[A-Za-z], )?--[a-z0-9-]+' | grep -oE -- '--[a-z0-9-]+'); do
        sed 's/\\-/-/g' "$1" | grep -qF -- "$opt" || { echo "$1: no $opt"; missing=1; }
    done
    return $missing
}
page_names() { sed 's/\\-/-/g' "$1" | grep -qF -- "$2"; }
renders_clean() { ! command -v groff >/dev/null || test -z "$(groff -man -Tutf8 -ww -z "$1" 2>&1)"; }
for cmd in $commands; do
    check test -f "$mandir/ilf-$cmd.1"
    check page_has_options "$mandir/ilf-$cmd.1" "$cmd"
    check renders_clean "$mandir/ilf-$cmd.1"
    check page_names "$mandir/ilf.1" "ilf-$cmd"   # in its SEE ALSO
done
# the Python package ilfkit (when the build has it): imported from the prefix alone, by Debian's python3,
# with no environment but PATH and PYTHONPATH; its module finds the installed liblfio through its rpath
if [ -d "$build/python/ilfkit" ]; then
    pydir=$(find "$prefix" -name '_ilfkit*.so' -printf '%h\n' | head -1)
    check test -n "$pydir" -a -f "$pydir/__init__.py"
    check env -i PATH=/usr/bin:/bin PYTHONPATH="$(dirname "${pydir:-.}")" /usr/bin/python3 -c "import ilfkit
s = ilfkit.open('$work/c.h5')[0]
assert abs(float(s.radiance.max()) - 1) < 1e-6, s.radiance.max()
assert ilfkit.__file__.startswith('$prefix/'), ilfkit.__file__"
fi
echo "$pass passed, $fail failed"
test "$fail" -eq 0
