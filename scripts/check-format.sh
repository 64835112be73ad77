#!/usr/bin/env bash
# Checks that every C++ source of the repository is formatted by clang-format (.clang-format:
# Google style, 100 columns) and lists the files that are not; exit 1 if any. `make format`
# formats them. Installs clang-format first if it is missing (scripts/install-deps.sh format).
set -euo pipefail
cd "$(dirname "$0")/.."
command -v clang-format >/dev/null 2>&1 || bash scripts/install-deps.sh format
# Tracked files and new ones not yet added (a file about to be committed is checked too).
mapfile -t files < <(git ls-files --cached --others --exclude-standard '*.cpp' '*.hpp' '*.inc' |
  grep -v '^tests/problems/malformed/')
bad=()
for f in "${files[@]}"; do
  clang-format --dry-run -Werror "$f" >/dev/null 2>&1 || bad+=("$f")
done
if [ ${#bad[@]} -gt 0 ]; then
  echo "check-format: ${#bad[@]} of ${#files[@]} files are not clang-formatted (run make format):"
  printf '  %s\n' "${bad[@]}"
  exit 1
fi
echo "check-format: ${#files[@]} files formatted"
