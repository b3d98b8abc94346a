# OpenCV for Keel: the three modules it uses (core, imgproc, imgcodecs).
#
# Debian ships OpenCVConfig.cmake only with the libopencv-dev metapackage, which pulls in
# every OpenCV module (VTK, Qt, ...). Keel installs just libopencv-{core,imgproc,imgcodecs}-dev,
# so when no config package is found this module defines the same imported targets
# (opencv_core, opencv_imgproc, opencv_imgcodecs) and OpenCV_LIBS from the headers and
# libraries those three packages install.
find_package(OpenCV QUIET NO_MODULE COMPONENTS core imgproc imgcodecs)
if(OpenCV_FOUND)
  set(KeelOpenCV_FOUND TRUE)
  return()
endif()

find_path(KEEL_OPENCV_INCLUDE_DIR opencv2/core.hpp PATH_SUFFIXES opencv4)
set(OpenCV_LIBS "")
foreach(module core imgproc imgcodecs)
  find_library(KEEL_OPENCV_${module}_LIBRARY opencv_${module})
  if(KEEL_OPENCV_${module}_LIBRARY AND KEEL_OPENCV_INCLUDE_DIR AND NOT TARGET opencv_${module})
    add_library(opencv_${module} SHARED IMPORTED GLOBAL)
    set_target_properties(opencv_${module} PROPERTIES
      IMPORTED_LOCATION "${KEEL_OPENCV_${module}_LIBRARY}"
      INTERFACE_INCLUDE_DIRECTORIES "${KEEL_OPENCV_INCLUDE_DIR}")
  endif()
  list(APPEND OpenCV_LIBS opencv_${module})
endforeach()
set(OpenCV_INCLUDE_DIRS "${KEEL_OPENCV_INCLUDE_DIR}")

include(FindPackageHandleStandardArgs)
find_package_handle_standard_args(KeelOpenCV
  REQUIRED_VARS KEEL_OPENCV_INCLUDE_DIR KEEL_OPENCV_core_LIBRARY KEEL_OPENCV_imgproc_LIBRARY
    KEEL_OPENCV_imgcodecs_LIBRARY)
set(OpenCV_FOUND ${KeelOpenCV_FOUND})
