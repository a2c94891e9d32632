# The web panel's tests, included by the top CMakeLists.txt inside its tests block (so
# RILBED_TEST_ENV and the rilbed target are there). Node and the npm packages of web/ and
# web/tests/ come from ./run (install_web_test_packages); without them each test fails and
# says so rather than being skipped.
find_program(NODE_EXECUTABLE node)

# rilbed_web_test(NAME LABEL TIMEOUT NEEDS [WORKING_DIRECTORY DIR] ARGS...): a test that runs
# `node ARGS...`, or, without Node, fails saying that ./run test installs NEEDS.
function(rilbed_web_test name label timeout needs)
  cmake_parse_arguments(PARSE_ARGV 4 web "" "WORKING_DIRECTORY" "")
  if(NODE_EXECUTABLE)
    if(web_WORKING_DIRECTORY)
      add_test(NAME ${name} COMMAND ${NODE_EXECUTABLE} ${web_UNPARSED_ARGUMENTS} WORKING_DIRECTORY ${web_WORKING_DIRECTORY})
    else()
      add_test(NAME ${name} COMMAND ${NODE_EXECUTABLE} ${web_UNPARSED_ARGUMENTS})
    endif()
  else()
    add_test(NAME ${name}
      COMMAND sh -c "echo '${name}: no node on the PATH when CMake ran: run ./run test (it installs ${needs})'; exit 1")
  endif()
  set_tests_properties(${name} PROPERTIES LABELS ${label} TIMEOUT ${timeout} ENVIRONMENT "${RILBED_TEST_ENV}")
endfunction()

set(_web_tests ${CMAKE_SOURCE_DIR}/web/tests)
set(_scenarios ${CMAKE_SOURCE_DIR}/scenarios)

# The web panel's server as a Foxglove client sees it (protocol_test.js, with
# @foxglove/ws-protocol): `rilbed run --gui`'s channels, poses and console.
rilbed_web_test(web_protocol e2e 300 "Node and the npm packages"
  ${_web_tests}/protocol_test.js $<TARGET_FILE:rilbed> ${_scenarios}/convoy_mixed.yaml)

# The web panel in a browser (browser_test.js: playwright-core driving Debian's
# /usr/bin/chromium) against `rilbed run --gui` with emulated real robots: the page, the
# live view's robots, Pause/Start, the real-time factor (on convoy_sim), manual driving,
# a closed tab stopping its robot, Exit; then robot bodies (a scenario of its own with
# `model: square` and `model: epuck` robots: each drawn as its own outline or disc, kept by
# "Start from this run"). Screenshots go to ${CMAKE_BINARY_DIR}/web-artifacts (or
# $RILBED_ARTIFACTS).
rilbed_web_test(web_browser e2e 300 "Node, the npm packages and Chromium"
  ${_web_tests}/browser_test.js $<TARGET_FILE:rilbed> ${_scenarios}/convoy_mixed.yaml ${_scenarios}/convoy_sim.yaml
  ${CMAKE_BINARY_DIR}/web-artifacts)

# The web panel's vision settings (vision_test.js, in Chromium) against `rilbed run --gui`
# with emulated real robots: the Vision section, brightness and contrast seen in the camera
# layer, min score 1 emptying the detections, refusals, a second page following, greyed
# without a camera.
rilbed_web_test(web_vision e2e 300 "Node, the npm packages and Chromium"
  ${_web_tests}/vision_test.js $<TARGET_FILE:rilbed> ${_scenarios}/convoy_mixed.yaml ${_scenarios}/convoy_sim.yaml
  ${CMAKE_BINARY_DIR}/web-artifacts)

# The page's scenario editor (editor_test.js, in Chromium) against `rilbed run --gui` on
# convoy_sim: a scenario started from the run, edited with the mouse and saved, which
# `rilbed run` accepts; the controller lists and forms from the server's registry; every
# scenarios/*.yaml loaded and saved unchanged, and one of robots with model:, body: and
# wheels:, drawn by their bodies. It needs web/node_modules too (js-yaml).
rilbed_web_test(web_editor e2e 300 "Node, the npm packages and Chromium"
  ${_web_tests}/editor_test.js $<TARGET_FILE:rilbed> ${CMAKE_BINARY_DIR}/web-artifacts)

# The page's pure helpers in Node (unit/*.test.mjs, node's test runner): the projection, ID
# lists, angles, geometry, robot bodies, the scenario checks against a controller registry
# fixture, the scenario's YAML read and written (with web/node_modules' js-yaml, as the
# page does), the Foxglove client against a stand-in WebSocket. No build, no browser. node --test runs in
# that folder and finds its *.test.mjs there itself, since a folder given as an argument is
# searched by Node 20 but taken for a test file by Node 22.
rilbed_web_test(web_unit web 120 "Node and the npm packages" WORKING_DIRECTORY ${_web_tests}/unit --test)

# ESLint over the web panel's JavaScript (lint.js with eslint.config.js: eslint's
# recommended rules and a few that catch bugs, over web/*.js and web/tests/).
rilbed_web_test(web_lint web 120 "Node and the npm packages" ${_web_tests}/lint.js)
