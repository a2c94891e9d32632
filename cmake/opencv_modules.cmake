# OpenCV's modules without OpenCV's CMake package: for the vision-only build
# (RILBED_VISION_ONLY) on a sysroot that holds the headers and libraries of the modules the
# vision module uses but not libopencv-dev, whose OpenCVConfig.cmake wants every module
# installed (`./run arm`'s arm64 sysroot). Sets OpenCV_FOUND, OpenCV_VERSION,
# OpenCV_INCLUDE_DIRS and OpenCV_LIBS (imported targets opencv_<module>) as the package
# does, for the modules in RILBED_OPENCV_MODULES.
find_path(RILBED_OPENCV_INCLUDE_DIR opencv2/core.hpp PATH_SUFFIXES opencv4 REQUIRED)
# Debian keeps the configuration headers (cvconfig.h) in the multiarch include directory.
find_path(RILBED_OPENCV_CONFIG_INCLUDE_DIR cvconfig.h PATH_SUFFIXES opencv4 ${CMAKE_LIBRARY_ARCHITECTURE}/opencv4)
set(OpenCV_INCLUDE_DIRS ${RILBED_OPENCV_INCLUDE_DIR})
if(RILBED_OPENCV_CONFIG_INCLUDE_DIR)
  list(APPEND OpenCV_INCLUDE_DIRS ${RILBED_OPENCV_CONFIG_INCLUDE_DIR})
endif()
file(STRINGS ${RILBED_OPENCV_INCLUDE_DIR}/opencv2/core/version.hpp _cv_version_lines
     REGEX "^#define CV_VERSION_(MAJOR|MINOR|REVISION) ")
string(REGEX REPLACE ".*MAJOR +([0-9]+).*MINOR +([0-9]+).*REVISION +([0-9]+).*" "\\1.\\2.\\3" OpenCV_VERSION
       "${_cv_version_lines}")
set(OpenCV_LIBS "")
foreach(_cv_module IN LISTS RILBED_OPENCV_MODULES)
  find_library(RILBED_OPENCV_${_cv_module}_LIBRARY opencv_${_cv_module} REQUIRED)
  add_library(opencv_${_cv_module} SHARED IMPORTED)
  set_target_properties(opencv_${_cv_module} PROPERTIES IMPORTED_LOCATION ${RILBED_OPENCV_${_cv_module}_LIBRARY}
                                                        INTERFACE_INCLUDE_DIRECTORIES "${OpenCV_INCLUDE_DIRS}")
  list(APPEND OpenCV_LIBS opencv_${_cv_module})
endforeach()
set(OpenCV_FOUND TRUE)
message(STATUS "OpenCV ${OpenCV_VERSION} modules without OpenCVConfig.cmake: ${OpenCV_LIBS} (${RILBED_OPENCV_INCLUDE_DIR})")
