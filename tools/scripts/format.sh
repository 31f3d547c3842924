#!/usr/bin/env bash
# Formats every C++ file of the repository with its .clang-format (clang-format from Debian 12);
# `tools/scripts/format.sh --check` changes nothing and fails, listing the files, when one is not formatted.
set -euo pipefail
cd "$(dirname "$0")/../.."
command -v clang-format >/dev/null || {
  echo "format: clang-format is not installed (apt-get install clang-format)" >&2
  exit 2
}
mapfile -t files < <(git ls-files '*.cc' '*.h' '*.c')
if [ "${1:-}" = --check ]; then
  bad=()
  for f in "${files[@]}"; do
    clang-format --dry-run --Werror "$f" >/dev/null 2>&1 || bad+=("$f")
  done
  if ((${#bad[@]})); then
    echo "format: not formatted (run tools/scripts/format.sh): ${bad[*]}" >&2
    exit 1
  fi
  echo "format: ${#files[@]} files formatted"
else
  clang-format -i "${files[@]}"
fi
