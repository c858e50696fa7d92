#!/bin/sh
# ilfkit.sh - set up, build and run ilfkit on Debian 12.
#
#   ./ilfkit.sh demo   install what is missing, build, run the main job on the default data
#   ./ilfkit.sh test   install what is missing, build, run the whole test suite
#
# Environment: BUILD_DIR (default build), OUT_DIR (default out), JOBS (default: all cores).
set -eu
cd "$(dirname "$0")"
BUILD_DIR=${BUILD_DIR:-build}
OUT_DIR=${OUT_DIR:-out}
JOBS=${JOBS:-$(nproc)}

PACKAGES="cmake make gcc g++ pkg-config libhdf5-dev hdf5-tools libembree-dev libopenexr-dev
libopenimageio-dev libpng-dev libcjson-dev libassimp-dev python3 python3-h5py python3-numpy python3-dev python3-pytest clang gnuplot-nox"

install_missing() {
    missing=""
    for p in $PACKAGES; do
        dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing="$missing $p"
    done
    [ -z "$missing" ] && return 0
    if [ "$(id -u)" -ne 0 ]; then
        echo "ilfkit.sh: missing Debian packages:$missing" >&2
        echo "ilfkit.sh: run as root, or: sudo apt-get install -y$missing" >&2
        exit 2
    fi
    echo "ilfkit.sh: installing:$missing" >&2
    DEBIAN_FRONTEND=noninteractive apt-get update -qq
    # shellcheck disable=SC2086
    DEBIAN_FRONTEND=noninteractive apt-get install -y -qq $missing >/dev/null
}

build() {
    cmake -S . -B "$BUILD_DIR" -DCMAKE_BUILD_TYPE=Release ${CMAKE_ARGS:-} >/dev/null
    cmake --build "$BUILD_DIR" -j "$JOBS"
}

demo() {
    ilf="$BUILD_DIR/tools/ilf"
    mkdir -p "$OUT_DIR"
    # The paper's 'beams' room, lit by the incident light field data/beams_lightfield.h5:
    # direct light and two bounces, radiance maps, statistics and the camera's view.
    "$ilf" relight data/beams.json -o "$OUT_DIR/beams"
    # The light field itself: its directions at the slab's centre, and the slab seen along its normal.
    "$ilf" slice data/beams_lightfield.h5 --position 8,8 --layout unfold -o "$OUT_DIR/lightfield_directions.png"
    "$ilf" slice data/beams_lightfield.h5 --toward 0,0,1 -o "$OUT_DIR/lightfield_spatial.png"
    echo "ilfkit.sh: the relit image is $OUT_DIR/beams/view.png (radiance in $OUT_DIR/beams/view.exr)"
}

case "${1:-}" in
demo) install_missing; build; demo ;;
test) install_missing; build; cd "$BUILD_DIR" && ctest --output-on-failure -j "$JOBS" ;;
*) echo "usage: ./ilfkit.sh demo|test" >&2; exit 2 ;;
esac
