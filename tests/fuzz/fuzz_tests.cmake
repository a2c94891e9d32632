# The fuzz tests, included by the main CMakeLists.txt (with the tests on). The targets
# are a project of their own (tests/fuzz/CMakeLists.txt) built with clang++, since
# libFuzzer needs clang and the main build uses the default compiler. CTest builds it:
#   fuzz_build          configures and builds it in <build>/fuzz (the fixture rilbed_fuzz;
#                       CTest runs it first whenever a fuzz test is asked for)
#   fuzz_khepera_reply  each target runs RILBED_FUZZ_SECONDS seconds (default 20), from its
#   fuzz_scenario       seeds and its working corpus <build>/fuzz/corpus/<target>; a crash,
#   fuzz_lcm_messages   leak, sanitizer report, broken invariant or hang fails the test and
#   fuzz_lcm_log        leaves the input in <build>/fuzz/artifacts/
#   fuzz_console_command
#   fuzz_foxglove_messages
#   fuzz_agent_messages
#   fuzz_plugin_answers
#   fuzz_sensor_parameters
#   fuzz_python_answers
# All have the label `fuzz`: `ctest -L fuzz` runs only them, `ctest -LE fuzz` all but them.
# Without clang++ or libFuzzer, configuring says so and the fuzz tests show as disabled.

set(RILBED_FUZZ_SECONDS 20 CACHE STRING "How long CTest runs each fuzz target, seconds")
if(NOT RILBED_FUZZ_SECONDS MATCHES "^[1-9][0-9]*$")
  # 0 would mean "forever" to libFuzzer.
  message(FATAL_ERROR "RILBED_FUZZ_SECONDS must be a whole number of seconds above 0, not '${RILBED_FUZZ_SECONDS}'")
endif()
find_program(RILBED_FUZZ_CXX NAMES clang++ clang++-14 DOC "clang++ for the fuzz targets (tests/fuzz)")

set(_fuzz_dir ${CMAKE_CURRENT_LIST_DIR})
set(_fuzz_bin ${CMAKE_BINARY_DIR}/fuzz)
set(_fuzz_targets fuzz_khepera_reply fuzz_scenario fuzz_lcm_messages fuzz_lcm_log fuzz_console_command fuzz_foxglove_messages
    fuzz_agent_messages fuzz_plugin_answers fuzz_sensor_parameters fuzz_python_answers)
# Seeds per target, read but never written (the fuzzer adds to the first corpus folder
# only, the working one in the build tree). The scenarios ship with the project.
set(_fuzz_seeds_fuzz_khepera_reply ${_fuzz_dir}/corpus/khepera_reply)
set(_fuzz_seeds_fuzz_scenario ${PROJECT_SOURCE_DIR}/scenarios)
set(_fuzz_seeds_fuzz_lcm_messages ${_fuzz_dir}/corpus/lcm_messages)
set(_fuzz_seeds_fuzz_lcm_log ${_fuzz_dir}/corpus/lcm_log)
set(_fuzz_seeds_fuzz_console_command ${_fuzz_dir}/corpus/console_command)
set(_fuzz_seeds_fuzz_foxglove_messages ${_fuzz_dir}/corpus/foxglove_messages)
set(_fuzz_seeds_fuzz_agent_messages ${_fuzz_dir}/corpus/agent_messages)
set(_fuzz_seeds_fuzz_plugin_answers ${_fuzz_dir}/corpus/plugin_answers)
set(_fuzz_seeds_fuzz_sensor_parameters ${_fuzz_dir}/corpus/sensor_parameters)
set(_fuzz_seeds_fuzz_python_answers ${_fuzz_dir}/corpus/python_answers)
set(_fuzz_dict_fuzz_khepera_reply ${_fuzz_dir}/khepera_reply.dict)
set(_fuzz_dict_fuzz_scenario ${_fuzz_dir}/scenario.dict)
set(_fuzz_dict_fuzz_lcm_messages ${_fuzz_dir}/lcm_messages.dict)
set(_fuzz_dict_fuzz_lcm_log ${_fuzz_dir}/lcm_log.dict)
set(_fuzz_dict_fuzz_console_command ${_fuzz_dir}/console_command.dict)
set(_fuzz_dict_fuzz_foxglove_messages ${_fuzz_dir}/foxglove_messages.dict)
set(_fuzz_dict_fuzz_agent_messages ${_fuzz_dir}/agent_messages.dict)
set(_fuzz_dict_fuzz_plugin_answers ${_fuzz_dir}/plugin_answers.dict)
set(_fuzz_dict_fuzz_sensor_parameters ${_fuzz_dir}/sensor_parameters.dict)
set(_fuzz_dict_fuzz_python_answers ${_fuzz_dir}/python_answers.dict)
# The embedded interpreter lives until exit (it is never finalised): its allocations are not
# leaks, of an input's or at exit.
set(_fuzz_args_fuzz_python_answers -detect_leaks=0)
set(_fuzz_env_fuzz_python_answers ASAN_OPTIONS=detect_leaks=0)

# Can clang++ link a fuzzer? (On Debian libFuzzer comes apart, in libclang-rt-14-dev.)
set(_fuzz_problem "")
if(NOT RILBED_FUZZ_CXX)
  set(_fuzz_problem "clang++ was not found")
else()
  set(_check_dir ${CMAKE_BINARY_DIR}/fuzz-check)
  file(WRITE ${_check_dir}/check.cpp
       "#include <cstddef>\n#include <cstdint>\n"
       "extern \"C\" int LLVMFuzzerTestOneInput(const std::uint8_t*, std::size_t) { return 0; }\n")
  execute_process(
    COMMAND ${RILBED_FUZZ_CXX} -fsanitize=fuzzer,address,undefined check.cpp -o check
    WORKING_DIRECTORY ${_check_dir}
    RESULT_VARIABLE _check_result OUTPUT_VARIABLE _check_output ERROR_VARIABLE _check_output)
  if(NOT _check_result EQUAL 0)
    string(STRIP "${_check_output}" _check_output)
    set(_fuzz_problem "${RILBED_FUZZ_CXX} cannot link -fsanitize=fuzzer,address,undefined (is libFuzzer installed?): ${_check_output}")
  endif()
endif()

if(_fuzz_problem)
  message(WARNING "Fuzz tests disabled: ${_fuzz_problem}.\n"
                  "Install clang and libclang-rt-14-dev (`./run test` does) and configure again.")
  foreach(_target IN LISTS _fuzz_targets)
    add_test(NAME ${_target} COMMAND ${CMAKE_COMMAND} -E echo "disabled: ${_fuzz_problem}")
    set_tests_properties(${_target} PROPERTIES DISABLED TRUE LABELS fuzz)
  endforeach()
else()
  message(STATUS "Fuzz tests: ${_fuzz_targets} with ${RILBED_FUZZ_CXX}, ${RILBED_FUZZ_SECONDS} s each")
  string(REPLACE ";" "," _fuzz_target_list "${_fuzz_targets}")
  add_test(NAME fuzz_build
           COMMAND ${CMAKE_COMMAND} -DFUZZ_SOURCE_DIR=${_fuzz_dir} -DFUZZ_BINARY_DIR=${_fuzz_bin}
                   -DFUZZ_CXX=${RILBED_FUZZ_CXX} "-DFUZZ_GENERATOR=${CMAKE_GENERATOR}" -DFUZZ_JOBS=1
                   -DFUZZ_TARGETS=${_fuzz_target_list} -P ${_fuzz_dir}/build_fuzzers.cmake)
  # COST: CTest starts the dearest tests first, and on a clean clone (no timings recorded
  # yet) every test costs 0, so the build, declared last, started last and then ran for
  # minutes on one core with nothing beside it. Started first, it runs beside the others.
  set_tests_properties(fuzz_build PROPERTIES FIXTURES_SETUP rilbed_fuzz LABELS fuzz TIMEOUT 1200 COST 100000)
  foreach(_target IN LISTS _fuzz_targets)
    # Through `cmake -E env`: the target exists only once fuzz_build has run.
    add_test(NAME ${_target}
             COMMAND ${CMAKE_COMMAND} -E env UBSAN_OPTIONS=print_stacktrace=1 ${_fuzz_env_${_target}}
                     ${_fuzz_bin}/${_target} ${_fuzz_bin}/corpus/${_target} ${_fuzz_seeds_${_target}}
                     -dict=${_fuzz_dict_${_target}} ${_fuzz_args_${_target}}
                     -max_total_time=${RILBED_FUZZ_SECONDS} -rss_limit_mb=2048 -timeout=10
                     -print_final_stats=1 -artifact_prefix=${_fuzz_bin}/artifacts/${_target}-
             WORKING_DIRECTORY ${_fuzz_bin})
    math(EXPR _timeout "${RILBED_FUZZ_SECONDS} + 120")
    set_tests_properties(${_target} PROPERTIES
      FIXTURES_REQUIRED rilbed_fuzz LABELS fuzz TIMEOUT ${_timeout} COST 1000)
  endforeach()
endif()
