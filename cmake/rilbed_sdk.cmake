# Lays out rilbed's SDK in ${CMAKE_BINARY_DIR}/sdk at configure time (and again whenever a
# header or template changes, since configure_file makes cmake re-run then):
#   sdk/include/rilbed/*.h, *.hpp        the headers, the plug-in ABI's one definition
#   sdk/lib/pkgconfig/rilbed.pc          PKG_CONFIG_PATH=<build>/sdk/lib/pkgconfig pkg-config --cflags rilbed
#   sdk/lib/cmake/rilbed/rilbed*.cmake   find_package(rilbed) with CMAKE_PREFIX_PATH=<build>/sdk
# Both are relocatable: they find the headers relative to themselves.
set(RILBED_SDK_DIR ${CMAKE_BINARY_DIR}/sdk)
set(RILBED_SDK_HEADERS
  plugin.h
  rilbed_controller.h
  controller.hpp
  sensor_model.h
  actuator_model.h
)
foreach(header IN LISTS RILBED_SDK_HEADERS)
  configure_file(${CMAKE_CURRENT_SOURCE_DIR}/sdk/include/rilbed/${header} ${RILBED_SDK_DIR}/include/rilbed/${header} COPYONLY)
endforeach()
file(READ ${CMAKE_CURRENT_SOURCE_DIR}/sdk/include/rilbed/plugin.h RILBED_PLUGIN_H)
string(REGEX MATCH "#define RILBED_ABI_VERSION ([0-9]+)u" _ "${RILBED_PLUGIN_H}")
set(RILBED_ABI_VERSION ${CMAKE_MATCH_1})
configure_file(${CMAKE_CURRENT_SOURCE_DIR}/sdk/rilbed.pc.in ${RILBED_SDK_DIR}/lib/pkgconfig/rilbed.pc @ONLY)
configure_file(${CMAKE_CURRENT_SOURCE_DIR}/sdk/cmake/rilbedConfig.cmake.in ${RILBED_SDK_DIR}/lib/cmake/rilbed/rilbedConfig.cmake @ONLY)
include(CMakePackageConfigHelpers)
write_basic_package_version_file(${RILBED_SDK_DIR}/lib/cmake/rilbed/rilbedConfigVersion.cmake
  VERSION ${PROJECT_VERSION} COMPATIBILITY SameMinorVersion)

# rilbed_add_plugin(TARGET FILE_NAME SOURCES...): one of rilbed's own plug-in libraries,
# built as a lab builds one (the SDK's headers only, symbols hidden but the exported ones)
# into plugins/FILE_NAME.so beside the rilbed executable.
add_custom_target(rilbed_plugins)
function(rilbed_add_plugin target file_name)
  add_library(${target} MODULE ${ARGN})
  target_include_directories(${target} PRIVATE ${RILBED_SDK_DIR}/include)
  set_target_properties(${target} PROPERTIES
    OUTPUT_NAME ${file_name} PREFIX "" SUFFIX ".so"
    LIBRARY_OUTPUT_DIRECTORY ${CMAKE_BINARY_DIR}/plugins
    C_VISIBILITY_PRESET hidden CXX_VISIBILITY_PRESET hidden)
  add_dependencies(rilbed_plugins ${target})
endfunction()
