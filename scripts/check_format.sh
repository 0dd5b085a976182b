#!/usr/bin/env bash
# Checks that every C++ source follows .clang-format (clang-format 14, Debian 12's).
#   scripts/check_format.sh          list the files that differ; exit 1 if any
#   scripts/check_format.sh --fix    rewrite them in place
set -euo pipefail
root=$(cd "$(dirname "$0")/.." && pwd)
command -v clang-format >/dev/null || { echo "check_format: clang-format is not installed (scripts/setup.sh installs it)" >&2; exit 1; }
cd "$root"
mapfile -t files < <(find bench client core fuzz server tests tools -type f \( -name '*.cpp' -o -name '*.hpp' -o -name '*.h' \) | sort)
if [ "${1:-}" = --fix ]; then
  clang-format -i "${files[@]}"
  exit 0
fi
mapfile -t differ < <(clang-format --dry-run "${files[@]}" 2>&1 |
  sed -n 's/^\([^:]*\):[0-9]*:[0-9]*: warning: code should be clang-formatted.*/\1/p' | sort -u)
if [ ${#differ[@]} -gt 0 ]; then
  echo "check_format: ${#differ[@]} of ${#files[@]} files differ from .clang-format (fix: scripts/check_format.sh --fix):" >&2
  printf '  %s\n' "${differ[@]}" >&2
  exit 1
fi
echo "check_format: ${#files[@]} files follow .clang-format"
