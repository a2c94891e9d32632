# Configures (the first time) and builds the fuzz project; run by the CTest test
# fuzz_build, the fixture every fuzz test requires (see fuzz_tests.cmake):
#   cmake -DFUZZ_SOURCE_DIR=tests/fuzz -DFUZZ_BINARY_DIR=build/fuzz -DFUZZ_CXX=clang++
#         [-DFUZZ_GENERATOR=Ninja] [-DFUZZ_JOBS=1] [-DFUZZ_TARGETS=a,b]
#         -P tests/fuzz/build_fuzzers.cmake
# Also makes each target's working corpus (FUZZ_BINARY_DIR/corpus/<target>, where the
# fuzzer keeps what it learns between runs) and the folder for crashing inputs.
cmake_minimum_required(VERSION 3.25)

foreach(var FUZZ_SOURCE_DIR FUZZ_BINARY_DIR FUZZ_CXX)
  if(NOT DEFINED ${var})
    message(FATAL_ERROR "build_fuzzers.cmake: -D${var}=... is required")
  endif()
endforeach()
if(NOT DEFINED FUZZ_JOBS)
  set(FUZZ_JOBS 1)
endif()

if(NOT EXISTS "${FUZZ_BINARY_DIR}/CMakeCache.txt")
  set(generator "")
  if(FUZZ_GENERATOR)
    set(generator -G "${FUZZ_GENERATOR}")
  endif()
  execute_process(
    COMMAND "${CMAKE_COMMAND}" -S "${FUZZ_SOURCE_DIR}" -B "${FUZZ_BINARY_DIR}" ${generator}
            "-DCMAKE_CXX_COMPILER=${FUZZ_CXX}"
    COMMAND_ERROR_IS_FATAL ANY)
endif()
# Incremental; re-runs the configure step itself when tests/fuzz/CMakeLists.txt changed.
execute_process(COMMAND "${CMAKE_COMMAND}" --build "${FUZZ_BINARY_DIR}" -j "${FUZZ_JOBS}" COMMAND_ERROR_IS_FATAL ANY)

file(MAKE_DIRECTORY "${FUZZ_BINARY_DIR}/artifacts")
string(REPLACE "," ";" targets "${FUZZ_TARGETS}")
foreach(target IN LISTS targets)
  file(MAKE_DIRECTORY "${FUZZ_BINARY_DIR}/corpus/${target}")
endforeach()
