#!/usr/bin/env bash
# Checks that every C++ source of the repository is formatted as .clang-format says.
#   bash tools/check-format.sh          lists the files that differ, exit 1 if any (ctest: format_check)
#   bash tools/check-format.sh --fix    formats them in place
set -euo pipefail
cd "$(dirname "$0")/.."
command -v clang-format >/dev/null || { echo "check-format: clang-format is not installed (tools/install-deps.sh)" >&2; exit 2; }
mapfile -t files < <(find framework plugins models devices tools tests python -name '*.cpp' -o -name '*.hpp' | sort)
if [[ "${1:-}" == "--fix" ]]; then
  clang-format -i --style=file "${files[@]}"
  exit 0
fi
bad=0
for f in "${files[@]}"; do
  if ! clang-format --style=file --dry-run --Werror "$f" >/dev/null 2>&1; then
    echo "not formatted: $f (bash tools/check-format.sh --fix)"
    bad=1
  fi
done
exit $bad
