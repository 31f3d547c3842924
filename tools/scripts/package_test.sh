#!/usr/bin/env bash
# The Debian package as an administrator and a user meet it: builds it (setup.sh package),
# installs it with `apt-get install ./grove_*.deb`, then, in an empty directory with a bare
# environment and no checkout on any path, runs the quick start from /usr/bin/grove, reads
# `man grove`, builds the C++ example (CMake, shared and static) and the C example (pkg-config,
# no rpath, no LD_LIBRARY_PATH) against /usr, imports the Python module with /usr/bin/python3,
# and finally removes the package and checks that none of its files is left.
# Installs into /usr system-wide: run it as root on a throwaway machine (CI does), never where a
# grove package is installed already. Environment: BUILD_DIR as for setup.sh package.
set -euo pipefail
cd "$(dirname "$0")/../.."
src=$PWD
build_dir="${BUILD_DIR:-build-package}"
if [ "$(id -u)" -ne 0 ]; then
  echo "package_test: installs into /usr; run as root on a throwaway machine" >&2
  exit 2
fi
if dpkg-query -W -f='${Status}' grove 2>/dev/null | grep -q installed; then
  echo "package_test: a grove package is installed already; remove it first" >&2
  exit 2
fi

tools/scripts/setup.sh package
debs=("$build_dir"/grove_*_"$(dpkg --print-architecture)".deb)
[ "${#debs[@]}" -eq 1 ] || { echo "FAIL: not one package in $build_dir: ${debs[*]}" >&2; exit 1; }
deb=$(realpath "${debs[0]}")
work=$(mktemp -d)
chmod 755 "$work"
files=$work/files
dpkg-deb --fsys-tarfile "$deb" | tar -t | sed 's|^\./|/|; s|/$||' | grep -v '^/$' >"$files"
removed=0
cleanup() {
  [ "$removed" = 1 ] || DEBIAN_FRONTEND=noninteractive apt-get remove -y -qq grove >/dev/null 2>&1 || true
  rm -rf "$work"
}
trap cleanup EXIT

DEBIAN_FRONTEND=noninteractive apt-get install -y -qq --no-install-recommends "$deb" >/dev/null
echo "installed $(basename "$deb"): $(wc -l <"$files") paths"
# No file in the package that dpkg does not list as the package's.
listed=$(dpkg -L grove)
while read -r f; do
  grep -qxF "$f" <<<"$listed" || { echo "FAIL: $f not in dpkg -L grove" >&2; exit 1; }
done <"$files"

# The user's side: an empty directory, a bare environment, copies of the two example sources.
mkdir -p "$work/user/cpp" "$work/user/c"
cp "$src"/tools/examples/cpp_consumer/{CMakeLists.txt,walk.cc} "$work/user/cpp/"
cp "$src/tools/examples/c_walk/walk.c" "$work/user/c/"
cat >"$work/user/use.sh" <<'USE'
set -euo pipefail
cd "$HOME"
trap 'echo "FAIL at line $LINENO of the user steps" >&2; cat cpp.log >&2 2>/dev/null || true' ERR
[ "$(command -v grove)" = /usr/bin/grove ]
grove --version
grove footslam run --no-progress --out m >m.log
grep -q '"particles": 30000' m/summary.json
grove fastslam victoria-park --no-progress --out v >v.log
grep -q '"/usr/share/grove/victoria_park/inputs.dat.gz"' v/summary.json
# The manual holds every command's help (when dpkg is not set to leave man pages out).
if [ -e /usr/share/man/man1/grove.1.gz ] && command -v man >/dev/null; then
  man grove 2>/dev/null | grep -q 'grove fastslam victoria-park'
  man grove 2>/dev/null | grep -q '/usr/share/grove/victoria_park'
  echo "man grove: every command"
fi
# C++ through find_package(grove) from /usr, then C through pkg-config; libgrove.so from /usr
# (/lib on a merged-/usr system).
cmake -S cpp -B cpp/build -DCMAKE_BUILD_TYPE=Release >cpp.log 2>&1
cmake --build cpp/build >>cpp.log 2>&1
libs=$(ldd cpp/build/walk)
grep -qE 'libgrove\.so\.[0-9.]+ => (/usr)?/lib/' <<<"$libs"
cpp/build/walk /usr/share/grove/building_walk_steps.csv
cpp/build/walk_static /usr/share/grove/building_walk_steps.csv '{"particles": 1000, "seed": 3}'
cc -std=c99 -Wall -Wextra -Werror -pedantic c/walk.c $(pkg-config --cflags --libs grove) -o c/walk
c/walk /usr/share/grove/building_walk_steps.csv
/usr/bin/python3 -c 'import grove; print("python:", grove.__file__, grove.version()["string"]);
assert grove.__file__.startswith("/usr/lib/python3/dist-packages/")'
USE
env -i PATH=/usr/sbin:/usr/bin:/sbin:/bin HOME="$work/user" LANG=C.UTF-8 PYTHONDONTWRITEBYTECODE=1 \
  bash "$work/user/use.sh" || { echo "FAIL: the installed package did not work as above" >&2; exit 1; }

DEBIAN_FRONTEND=noninteractive apt-get remove -y -qq grove >/dev/null
removed=1
left=0
while read -r f; do
  # Directories other packages own (/usr/bin, ...) stay; the package's own must go.
  if [ -e "$f" ] || [ -L "$f" ]; then
    if [ -d "$f" ] && [ ! -L "$f" ] && dpkg -S "$f" >/dev/null 2>&1; then continue; fi
    echo "FAIL: left after apt-get remove: $f" >&2
    left=1
  fi
done <"$files"
[ "$left" = 0 ]
echo "package test passed"
