#!/usr/bin/env bash
# What the tools settle about rilbed's C++, checked (CTest `code_style`):
#  - every C and C++ file of src/, tests/ and bench/ is as clang-format (.clang-format) leaves it;
#  - clang-tidy (.clang-tidy) finds nothing in src/app, src/run, src/agents and src/session:
#    enumerators named kCamelCase, and no function longer than 120 lines.
#   tools/check_style.sh BUILD_DIR   (BUILD_DIR holds compile_commands.json)
set -uo pipefail
root="$(cd "$(dirname "$0")/.." && pwd)"
build="${1:?usage: check_style.sh BUILD_DIR}"
cd "$root"
status=0
mapfile -t files < <(git ls-files 'src/*.cpp' 'src/*.hpp' 'src/*.h' 'src/*.c' 'tests/*.cpp' 'tests/*.hpp' \
                                  'bench/*.cpp' 'bench/*.hpp' 2>/dev/null)
if ((${#files[@]} == 0)); then
  echo "check_style: no files listed (not a git checkout?)" >&2
  exit 1
fi
if ! clang-format --dry-run --Werror "${files[@]}" 2> /tmp/check_style_format.$$; then
  grep -E "^[^ ].*: (warning|error):" /tmp/check_style_format.$$ | sed 's/ \[-Wclang-format-violations\]//' | sort -u | head -50
  echo "check_style: the files above are not as clang-format leaves them: clang-format -i them" >&2
  status=1
fi
rm -f /tmp/check_style_format.$$
if [[ ! -f "$build/compile_commands.json" ]]; then
  echo "check_style: $build/compile_commands.json is missing (configure with CMake first)" >&2
  exit 1
fi
mapfile -t tidy_files < <(git ls-files 'src/app/*.cpp' 'src/run/*.cpp' 'src/agents/*.cpp' 'src/session/*.cpp')
out=$(run-clang-tidy -p "$build" -j "${RILBED_JOBS:-2}" -quiet "${tidy_files[@]}" 2>&1)
if grep -qE "(warning|error): " <<< "$out"; then
  grep -E "(warning|error): " <<< "$out" | sed 's/\x1b\[[0-9;]*m//g' | sort -u | head -50
  echo "check_style: clang-tidy found the above (see .clang-tidy)" >&2
  status=1
fi
exit $status
