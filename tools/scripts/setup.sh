#!/usr/bin/env bash
# Installs what grove needs from Debian's archive (only what is missing; quiet when nothing is),
# configures and builds, then does one job:
#   tools/scripts/setup.sh run    FootSLAM, 30,000 particles, on the bundled walk -> build/footslam/
#   tools/scripts/setup.sh test   every test (ctest)
#   tools/scripts/setup.sh build  just build
#   tools/scripts/setup.sh package  the Debian package (prefix /usr) -> build-package/grove_VERSION_ARCH.deb
# Environment: BUILD_DIR (default build), BUILD_TYPE (Release, Debug, RelWithDebInfo; default
# Release), SANITIZE=1 for the ASan + UBSan configuration (pooling off), EXTRA_CMAKE_ARGS for
# anything else (e.g. -DGROVE_BUILD_BENCHMARKS=OFF).
set -euo pipefail
cd "$(dirname "$0")/../.."

job="${1:-build}"
shift || true

packages=(cmake g++ make pkg-config libtbb-dev libeigen3-dev libjemalloc-dev libgtest-dev
  libbenchmark-dev libcli11-dev libfmt-dev nlohmann-json3-dev librandom123-dev libcairo2-dev
  zlib1g-dev libboost-dev gnuplot-nox libhwy-dev pybind11-dev python3-dev python3-numpy
  python3-matplotlib libopenmpi-dev openmpi-bin libmatio-dev)
# The package's man page and dependency list need help2man and dpkg-shlibdeps.
[ "$job" = package ] && packages+=(help2man dpkg-dev file)
missing=()
for p in "${packages[@]}"; do
  dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing+=("$p")
done
if ((${#missing[@]})); then
  echo "setup: installing ${missing[*]}" >&2
  sudo_cmd=()
  [ "$(id -u)" -eq 0 ] || sudo_cmd=(sudo)
  "${sudo_cmd[@]}" apt-get update -qq
  DEBIAN_FRONTEND=noninteractive "${sudo_cmd[@]}" apt-get install -y -qq --no-install-recommends \
    "${missing[@]}" >/dev/null
fi

build_dir="${BUILD_DIR:-build}"
# The package is configured for /usr: a build of its own, so build/ keeps its install layout.
[ "$job" = package ] && build_dir="${BUILD_DIR:-build-package}"
cmake_args=(-DCMAKE_BUILD_TYPE="${BUILD_TYPE:-Release}")
[ "$job" = package ] && cmake_args+=(-DCMAKE_INSTALL_PREFIX=/usr)
if [ "${SANITIZE:-0}" = 1 ]; then
  cmake_args+=(-DGROVE_SANITIZE=ON)
  export LSAN_OPTIONS="suppressions=$PWD/tools/scripts/lsan.supp:print_suppressions=0"
  export UBSAN_OPTIONS="print_stacktrace=1:halt_on_error=1"
fi
# shellcheck disable=SC2206  # word splitting intended
cmake_args+=(${EXTRA_CMAKE_ARGS:-})
cmake -S . -B "$build_dir" "${cmake_args[@]}" >/dev/null
cmake --build "$build_dir" -j "$(nproc)" -- --no-print-directory >/dev/null

case "$job" in
  run)
    "$build_dir/tools/grove" footslam run --particles 30000 --out "$build_dir/footslam" "$@"
    ;;
  test)
    ctest --test-dir "$build_dir" -j "$(nproc)" --output-on-failure "$@"
    ;;
  build) ;;
  package)
    rm -f "$build_dir"/grove_*.deb  # a package an earlier version left
    cmake --build "$build_dir" --target package -- --no-print-directory >/dev/null
    ls "$build_dir"/grove_*.deb
    ;;
  *)
    echo "usage: tools/scripts/setup.sh run|test|build|package [args]" >&2
    exit 2
    ;;
esac
