#!/bin/bash
# install_test.sh BUILD_DIR CONSUMER_SRC WORK_DIR
# Installs the build into a fresh prefix, then builds and runs a consumer of
# liblfio twice: through find_package(lfio) and through pkg-config; and, against
# the prefix only, a program that computes irradiance at points of a scene
# (librelight) and one that captures probe images into a light field (libcapture),
# each through find_package(ilfkit COMPONENTS ...) and through pkg-config. The
# installed headers stand alone (every include installed or standard C), and the
# installed libraries export their public prefix only. The
# installed ilf does not link OpenImageIO, writes a PNG and an EXR without it,
# and finds the installed image module (LIBDIR/ilfkit/libilfkit_oiio.so) to
# read the EXR back as a probe; it does not link assimp either, and finds the installed mesh module
# (LIBDIR/ilfkit/libilfkit_assimp.so) to relight a scene with an OBJ mesh. Nothing runs with LD_LIBRARY_PATH: the CMake packages, the .pc files'
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
expect_fail_with() {  # TEXT COMMAND...: COMMAND fails and its output names TEXT
    local text=$1 out; shift
    ! out=$("$@" 2>&1) && grep -qF -- "$text" <<<"$out"
}
libdir=$(find "$prefix" -name 'liblfio.so' -printf '%h\n' | head -1)
check test -x "$prefix/bin/ilf"
check test -x "$prefix/bin/ilf-bench"   # `ilf bench` runs it from ilf's own folder
check test -f "$prefix/include/lfio/lightfield.h"
check test -f "$libdir/pkgconfig/lfio.pc"
check test -f "$libdir/cmake/lfio/lfioConfig.cmake"
for f in relight/engine.h relight/scene.h relight/reference.h capture/capture.h ilf/limits.h; do
    check test -f "$prefix/include/$f"
done
check test -f "$libdir/pkgconfig/relight.pc" -a -f "$libdir/pkgconfig/capture.pc"
check test -f "$libdir/cmake/ilfkit/ilfkitConfig.cmake"
# Installed headers: each compiles alone, pedantic, from the prefix's include folder, and includes
# only standard C headers or headers installed beside it (no Embree, OpenImageIO, assimp, HDF5). An MPI
# build also installs lfio/radmap_mpi.h, which names MPI_Comm: it alone may include mpi.h, and compiles
# with MPI's include flags.
standard_c=" math.h stdarg.h stddef.h stdint.h stdio.h stdlib.h string.h "
mpi_flags=""
if test -f "$prefix/include/lfio/radmap_mpi.h"; then
    standard_c="$standard_c mpi.h "
    mpi_flags=$(mpicc --showme:compile 2>/dev/null || pkg-config --cflags ompi-c 2>/dev/null || true)
fi
includes_installed() {
    local bad=0
    for inc in $(grep -rhoE '^#[[:space:]]*include[[:space:]]*[<"][^>"]+' "$prefix/include" | sed -E 's/.*[<"]//' | sort -u); do
        [[ "$standard_c" == *" $inc "* ]] || test -f "$prefix/include/$inc" ||
            { echo "installed headers include $inc, which is neither standard C nor installed"; bad=1; }
    done
    return $bad
}
check includes_installed
header_alone() { printf '#include <%s>\nint header_alone;\n' "$1" |
                 cc -std=c99 -pedantic -Wall -Wextra -Werror -fsyntax-only -I"$prefix/include" $mpi_flags -x c -; }
for h in $(cd "$prefix/include" && ls relight/*.h capture/*.h lfio/*.h ilf/*.h); do
    check header_alone "$h"
done
# Exports: defined dynamic symbols are the library's public prefix (and its version node) only.
exports_only() {  # LIBRARY PREFIX
    local other
    other=$(nm -D --defined-only "$1" | awk '{ print $NF }' | grep -vE "^$2[a-z]|^[A-Z]+_0\$" || true)
    test -z "$other" || { echo "$1 exports more than $2*: $(echo $other | head -c 300)"; return 1; }
}
check exports_only "$libdir/liblfio.so" lfio_
check exports_only "$libdir/librelight.so" rl_
check exports_only "$libdir/libcapture.so" cap_
check test "$(ldd "$libdir/libcapture.so" | grep -c OpenImageIO)" -eq 0
# find_package
cmake -S "$src" -B "$work/cm" -DCMAKE_PREFIX_PATH="$prefix" > "$work/cm.log" 2>&1 || cat "$work/cm.log"
check cmake --build "$work/cm"
# the ilfkit package refuses a component it does not have
mkdir -p "$work/nosuch"
printf 'cmake_minimum_required(VERSION 3.18)\nproject(nosuch C)\nfind_package(ilfkit REQUIRED COMPONENTS relight nosuch)\n' \
    > "$work/nosuch/CMakeLists.txt"
check expect_fail_with "nosuch" cmake -S "$work/nosuch" -B "$work/nosuch/build" -DCMAKE_PREFIX_PATH="$prefix"
# Linking must carry the way to the library: every program below runs without LD_LIBRARY_PATH
# (find_package gives the library's full path, the .pc files an rpath).
unset LD_LIBRARY_PATH
check "$work/cm/consumer_cmake" "$work/a.h5"
# pkg-config
pc() { PKG_CONFIG_PATH="$libdir/pkgconfig" pkg-config "$@"; }
check cc -std=c99 -o "$work/consumer_pc" "$src/consumer.c" $(pc --cflags --libs lfio)
check "$work/consumer_pc" "$work/b.h5"
check "$prefix/bin/ilf" --version
# the image module: installed, loaded by the installed ilf on its first image, never linked
check test -f "$libdir/ilfkit/libilfkit_oiio.so"
check test "$(ldd "$prefix/bin/ilf" | grep -c OpenImageIO)" -eq 0
ilf() { env -u ILFKIT_IMAGE_MODULE -u ILFKIT_MESH_MODULE "$prefix/bin/ilf" "$@" >>"$work/ilf.log" 2>&1; }
check ilf synth --kind constant --grid 2x2 --n 2 -o "$work/c.h5"
check ilf slice "$work/c.h5" --toward 0,0,1 -o "$work/c.png"
check ilf slice "$work/c.h5" --position 0,0 --layout latlong -o "$work/c.exr"
check test -s "$work/c.png" -a -s "$work/c.exr"
printf '{"plane": {"origin": [0, 0, 0], "u": [1, 0, 0], "v": [0, 1, 0]}, "grid": {"nu": 1, "nv": 1}, "n": 2,
  "pattern": "c.exr"}\n' > "$work/probe.json"
check ilf capture "$work/probe.json" -o "$work/probe.h5" --quiet
check test -s "$work/probe.h5"
# the mesh module: installed beside the image module, loaded by the installed ilf on a scene's first mesh
check test -f "$libdir/ilfkit/libilfkit_assimp.so"
check test "$(ldd "$prefix/bin/ilf" | grep -c assimp)" -eq 0
check test "$(ldd "$libdir/librelight.so" | grep -c assimp)" -eq 0
printf 'v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nf 1 2 3 4\n' > "$work/floor.obj"
printf '{"materials": {"grey": {}}, "meshes": [{"file": "floor.obj", "material": "grey"}]}\n' > "$work/floor.json"
check ilf relight "$work/floor.json" -o "$work/floor" --quiet
check grep -q "floor.obj" <("$prefix/bin/ilf" info "$work/floor/radiance.h5")
# relight and capture from a program: find_package(ilfkit COMPONENTS ...) (built above) and pkg-config
check "$work/cm/consumer_irradiance_cmake" "$work/lamp_cm.json"
check env -u ILFKIT_IMAGE_MODULE "$work/cm/consumer_capture_cmake" "$work/probe.json" "$work/capture_cm.h5"
check cc -std=c99 -o "$work/irradiance_pc" "$src/consumer_irradiance.c" $(pc --cflags --libs relight) -lm
check "$work/irradiance_pc" "$work/lamp_pc.json"
check cc -std=c99 -o "$work/capture_pc" "$src/consumer_capture.c" $(pc --cflags --libs capture) -lm
check env -u ILFKIT_IMAGE_MODULE "$work/capture_pc" "$work/probe.json" "$work/capture_pc.h5"
check ilf verify "$work/capture_pc.h5"
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
# with no environment but PATH and PYTHONPATH; its module finds the installed liblfio through its rpath,
# and librelight.so finds the mesh module of the install it belongs to
if [ -d "$build/python/ilfkit" ]; then
    pydir=$(find "$prefix" -name '_ilfkit*.so' -printf '%h\n' | head -1)
    check test -n "$pydir" -a -f "$pydir/__init__.py"
    check env -i PATH=/usr/bin:/bin PYTHONPATH="$(dirname "${pydir:-.}")" /usr/bin/python3 -c "import ilfkit
s = ilfkit.open('$work/c.h5')[0]
assert abs(float(s.radiance.max()) - 1) < 1e-6, s.radiance.max()
assert len(ilfkit.relight('$work/floor.json').maps) == 1  # the mesh module found beside librelight.so
assert ilfkit.__file__.startswith('$prefix/'), ilfkit.__file__"
    # and its tests pass against the install alone: the installed package, the installed ilf as their reference
    if /usr/bin/python3 -c 'import pytest' 2>/dev/null; then
        check env -i PATH=/usr/bin:/bin PYTHONPATH="$(dirname "${pydir:-.}")" ILF="$prefix/bin/ilf" PYTHONDONTWRITEBYTECODE=1 \
            /usr/bin/python3 -m pytest -q -p no:cacheprovider --basetemp="$work/pytest" "$src/../python"
    fi
fi
echo "$pass passed, $fail failed"
test "$fail" -eq 0
