#!/usr/bin/env bash
# pip as a Python user meets it, without network: a venv made from Debian's python3 with
# --system-site-packages (numpy from python3-numpy), `pip install --no-build-isolation --no-index
# ./engine/bindings/python`, then, from an empty directory, `import grove` from the venv and a
# FootSLAM run on the bundled walk. Installs python3-venv and python3-wheel when missing (what
# setup.sh installs must be there). Writes nothing outside a temporary directory but the build
# folder build-pip/ (reused by a second run) and engine/bindings/python/grove.egg-info/.
set -euo pipefail
cd "$(dirname "$0")/../.."
src=$PWD
missing=()
for p in python3-venv python3-wheel python3-numpy; do
  dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing+=("$p")
done
if ((${#missing[@]})); then
  sudo_cmd=()
  [ "$(id -u)" -eq 0 ] || sudo_cmd=(sudo)
  "${sudo_cmd[@]}" apt-get update -qq
  DEBIAN_FRONTEND=noninteractive "${sudo_cmd[@]}" apt-get install -y -qq --no-install-recommends \
    "${missing[@]}" >/dev/null
fi
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT

/usr/bin/python3 -m venv --system-site-packages "$work/venv"
if ! "$work/venv/bin/pip" install --no-build-isolation --no-index "$src/engine/bindings/python" \
  >"$work/pip.log" 2>&1; then
  cat "$work/pip.log" >&2
  echo "FAIL: pip install" >&2
  exit 1
fi
mkdir "$work/empty"
cd "$work/empty"
"$work/venv/bin/python" - "$work/venv" "$src/tools/data/building_walk_steps.csv" <<'PY'
import math, sys
import numpy as np
import grove

venv, walk = sys.argv[1], sys.argv[2]
assert grove.__file__.startswith(venv + "/"), grove.__file__
steps = np.loadtxt(walk, delimiter=",", skiprows=1)
slam = grove.FootSlam(particles=2000, seed=1)
slam.run(steps)
pose = slam.mean_pose()
assert slam.steps == len(steps) and all(math.isfinite(v) for v in pose), pose
print(f"pip: grove {grove.__version__} from {grove.__file__}; {slam.steps} steps, "
      f"mean pose x {pose.x:.3f} m, y {pose.y:.3f} m")
PY
echo "pip test passed"
