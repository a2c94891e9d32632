#!/usr/bin/env bash
# What the tools settle about rilbed's C++, checked (CTest `code_style`):
#  - every C and C++ file of src/, tests/, bench/, sdk/ and examples/ is as clang-format (.clang-format)
#    leaves it;
#  - .clang-tidy's two rules (enumerators kCamelCase; no function in src/app, src/run,
#    src/agents and src/session longer than 120 lines), by tools/style_checks.py in a
#    second (clang-tidy itself takes minutes: `run-clang-tidy -p build` applies it all).
#   tools/check_style.sh
set -uo pipefail
root="$(cd "$(dirname "$0")/.." && pwd)"
cd "$root"
status=0
mapfile -t files < <(git ls-files 'src/*.cpp' 'src/*.hpp' 'src/*.h' 'src/*.c' 'tests/*.cpp' 'tests/*.hpp' \
                                  'bench/*.cpp' 'bench/*.hpp' 'tests/*.c' 'sdk/*.h' 'sdk/*.hpp' 'examples/*.c' \
                                  'examples/*.cpp' 2>/dev/null)
if ((${#files[@]} == 0)); then
  echo "check_style: no files listed (not a git checkout?)" >&2
  exit 1
fi
report="$(mktemp)"
if ! clang-format --dry-run --Werror "${files[@]}" 2> "$report"; then
  grep -E "^[^ ].*: (warning|error):" "$report" | cut -d: -f1 | sort -u | sed 's/$/: not as clang-format leaves it/'
  echo "check_style: clang-format -i the files above" >&2
  status=1
fi
rm -f "$report"
/usr/bin/python3 tools/style_checks.py "$root" || status=1
exit $status
