# The web panel's tests, included by the top CMakeLists.txt inside its tests block (so
# RILBED_TEST_ENV and the rilbed target are there). Node and the npm packages of web/ and
# web/tests/ come from ./run (install_web_test_packages); without them each test fails and
# says so rather than being skipped.
# The web panel's server as a Foxglove client sees it (web/tests/protocol_test.js, with
# @foxglove/ws-protocol): `rilbed run --gui`'s channels, poses and console (label e2e).
# Its npm packages are in web/tests/node_modules (./run installs them); without them, or
# without Node, the test fails and says so rather than being skipped.
find_program(NODE_EXECUTABLE node)
if(NODE_EXECUTABLE)
  add_test(NAME web_protocol
    COMMAND ${NODE_EXECUTABLE} ${CMAKE_SOURCE_DIR}/web/tests/protocol_test.js $<TARGET_FILE:rilbed>
            ${CMAKE_SOURCE_DIR}/scenarios/convoy_mixed.yaml)
else()
  add_test(NAME web_protocol
    COMMAND sh -c "echo 'web_protocol: no node on the PATH when CMake ran: run ./run test (it installs Node and the npm packages)'; exit 1")
endif()
set_tests_properties(web_protocol PROPERTIES LABELS e2e TIMEOUT 300 ENVIRONMENT "${RILBED_TEST_ENV}")

# The web panel in a browser (web/tests/browser_test.js: playwright-core driving Debian's
# /usr/bin/chromium) against `rilbed run --gui` with emulated real robots: the page, the
# live view's robots, Pause/Start, the real-time factor (on convoy_sim), manual driving,
# a closed tab stopping its robot, Exit (label e2e). Screenshots go to
# ${CMAKE_BINARY_DIR}/web-artifacts (or $RILBED_ARTIFACTS). Without Node, its npm
# packages or Chromium it fails and says that ./run test installs them.
if(NODE_EXECUTABLE)
  add_test(NAME web_browser
    COMMAND ${NODE_EXECUTABLE} ${CMAKE_SOURCE_DIR}/web/tests/browser_test.js $<TARGET_FILE:rilbed>
            ${CMAKE_SOURCE_DIR}/scenarios/convoy_mixed.yaml ${CMAKE_SOURCE_DIR}/scenarios/convoy_sim.yaml
            ${CMAKE_BINARY_DIR}/web-artifacts)
else()
  add_test(NAME web_browser
    COMMAND sh -c "echo 'web_browser: no node on the PATH when CMake ran: run ./run test (it installs Node, the npm packages and Chromium)'; exit 1")
endif()
set_tests_properties(web_browser PROPERTIES LABELS e2e TIMEOUT 300 ENVIRONMENT "${RILBED_TEST_ENV}")

# The web panel's vision settings (web/tests/vision_test.js: playwright-core driving Debian's
# /usr/bin/chromium) against `rilbed run --gui` with emulated real robots: the Vision
# section, brightness and contrast seen in the camera layer, min score 1 emptying the
# detections, refusals, a second page following, greyed without a camera (label e2e).
# Screenshots go to ${CMAKE_BINARY_DIR}/web-artifacts (or $RILBED_ARTIFACTS).
if(NODE_EXECUTABLE)
  add_test(NAME web_vision
    COMMAND ${NODE_EXECUTABLE} ${CMAKE_SOURCE_DIR}/web/tests/vision_test.js $<TARGET_FILE:rilbed>
            ${CMAKE_SOURCE_DIR}/scenarios/convoy_mixed.yaml ${CMAKE_SOURCE_DIR}/scenarios/convoy_sim.yaml
            ${CMAKE_BINARY_DIR}/web-artifacts)
else()
  add_test(NAME web_vision
    COMMAND sh -c "echo 'web_vision: no node on the PATH when CMake ran: run ./run test (it installs Node, the npm packages and Chromium)'; exit 1")
endif()
set_tests_properties(web_vision PROPERTIES LABELS e2e TIMEOUT 300 ENVIRONMENT "${RILBED_TEST_ENV}")

# The page's scenario editor (web/tests/editor_test.js: playwright-core driving Debian's
# /usr/bin/chromium) against `rilbed run --gui` on convoy_sim: a scenario started from the
# run, edited with the mouse and saved, which `rilbed run` accepts; every scenarios/*.yaml
# loaded and saved unchanged (label e2e). Its screenshot goes to
# ${CMAKE_BINARY_DIR}/web-artifacts (or $RILBED_ARTIFACTS). Without Node, the npm packages
# (web/tests/node_modules, and web/node_modules: the page's js-yaml) or Chromium it fails
# and says that ./run test installs them.
if(NODE_EXECUTABLE)
  add_test(NAME web_editor
    COMMAND ${NODE_EXECUTABLE} ${CMAKE_SOURCE_DIR}/web/tests/editor_test.js $<TARGET_FILE:rilbed>
            ${CMAKE_BINARY_DIR}/web-artifacts)
else()
  add_test(NAME web_editor
    COMMAND sh -c "echo 'web_editor: no node on the PATH when CMake ran: run ./run test (it installs Node, the npm packages and Chromium)'; exit 1")
endif()
set_tests_properties(web_editor PROPERTIES LABELS e2e TIMEOUT 300 ENVIRONMENT "${RILBED_TEST_ENV}")

# The page's pure helpers in Node (web/tests/unit/*.test.mjs, node's test runner): the
# projection, ID lists, angles, geometry, the scenario checks against a controller registry
# fixture, the Foxglove client against a stand-in WebSocket (label web). They need Node
# alone: no npm package, no build, no browser. node --test runs in that folder and finds
# its *.test.mjs there itself, since a folder given as an argument is searched by Node 20
# but taken for a test file by Node 22 and later.
if(NODE_EXECUTABLE)
  add_test(NAME web_unit COMMAND ${NODE_EXECUTABLE} --test WORKING_DIRECTORY ${CMAKE_SOURCE_DIR}/web/tests/unit)
else()
  add_test(NAME web_unit
    COMMAND sh -c "echo 'web_unit: no node on the PATH when CMake ran: run ./run test (it installs Node)'; exit 1")
endif()
set_tests_properties(web_unit PROPERTIES LABELS web TIMEOUT 120 ENVIRONMENT "${RILBED_TEST_ENV}")

# ESLint over the web panel's JavaScript (web/tests/lint.js with web/tests/eslint.config.js:
# eslint's recommended rules and a few that catch bugs, over web/*.js and web/tests/)
# (label web). eslint and its packages are in web/tests/node_modules (./run installs
# them); without them, or without Node, the test fails and says so rather than being
# skipped.
if(NODE_EXECUTABLE)
  add_test(NAME web_lint COMMAND ${NODE_EXECUTABLE} ${CMAKE_SOURCE_DIR}/web/tests/lint.js)
else()
  add_test(NAME web_lint
    COMMAND sh -c "echo 'web_lint: no node on the PATH when CMake ran: run ./run test (it installs Node and the npm packages)'; exit 1")
endif()
set_tests_properties(web_lint PROPERTIES LABELS web TIMEOUT 120 ENVIRONMENT "${RILBED_TEST_ENV}")
