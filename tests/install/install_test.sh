#!/usr/bin/env bash
# Installs grove into a fresh prefix and builds and runs consumers against it the way an embedder
# would, with nothing of the build or source tree on their include or library paths: the C++
# example project through find_package(grove) (shared and static), and the C example through
# pkg-config, and the Python module. Usage: install_test.sh BUILD_DIR SOURCE_DIR [python]
set -euo pipefail
build=$1
src=$2
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
# Quiet steps write to $log, shown when one fails.
log=$work/log
trap 'echo "FAIL at line $LINENO; the last quiet step printed:" >&2; cat "$log" >&2' ERR
prefix=$work/prefix
walk=$src/tools/data/building_walk_steps.csv

cmake --install "$build" --prefix "$prefix" >"$log" 2>&1
echo "installed into $prefix:"
(cd "$prefix" && find . -type f -o -type l | sort | sed 's/^/  /')

# The installed command reads its bundled data from the prefix, not from the source tree.
"$prefix/bin/grove" fastslam victoria-park --no-progress --particles 5 --until 5 \
  --out "$work/park" >"$log" 2>&1
grep -q "\"$prefix/share/grove/victoria_park/inputs.dat.gz\"" "$work/park/summary.json" ||
  { echo "FAIL: the installed grove did not read $prefix/share/grove" >&2; exit 1; }

# The installed headers name only installed headers.
if grep -rhoE '#include "[^"]+"' "$prefix/include/grove" | grep -v '"grove/'; then
  echo "FAIL: an installed header includes a private one" >&2
  exit 1
fi

# C++: find_package(grove 0.3 CONFIG REQUIRED), the shared and the static library.
cmake -S "$src/tools/examples/cpp_consumer" -B "$work/cpp" -DCMAKE_BUILD_TYPE=Release \
  -DCMAKE_PREFIX_PATH="$prefix" >"$log" 2>&1
cmake --build "$work/cpp" -- --no-print-directory >"$log" 2>&1
# (ldd's output is read whole first: `ldd | grep -q` can fail under pipefail when grep stops
# reading early.)
libs=$(ldd "$work/cpp/walk")
if ! grep -q "libgrove.so.* => $prefix/" <<<"$libs"; then
  echo "FAIL: walk does not load libgrove.so from the prefix:" >&2
  echo "$libs" >&2
  exit 1
fi
libs=$(ldd "$work/cpp/walk_static")
if grep -q libgrove <<<"$libs"; then
  echo "FAIL: walk_static loads libgrove.so" >&2
  exit 1
fi
"$work/cpp/walk" "$walk"
"$work/cpp/walk_static" "$walk" '{"particles": 1000, "seed": 3}'

# C99 through pkg-config.
export PKG_CONFIG_PATH=$(dirname "$(find "$prefix" -name grove.pc)")
libdir=$(pkg-config --variable=libdir grove)
cc -std=c99 -Wall -Wextra -Werror -pedantic "$src/tools/examples/c_walk/walk.c" -o "$work/c_walk" \
  $(pkg-config --cflags --libs grove) -Wl,-rpath,"$libdir"
"$work/c_walk" "$walk"

# Python: the module from the prefix, when this build has one (a third argument "python").
if [ "${3:-}" = python ]; then
  (cd "$work" && PYTHONPATH="$prefix/lib/python3/dist-packages" PYTHONDONTWRITEBYTECODE=1 \
    /usr/bin/python3 -c 'import grove, sys; print(grove.version()["string"]);
assert grove.__file__.startswith(sys.argv[1]), grove.__file__' "$prefix")
fi
echo "install test passed"
