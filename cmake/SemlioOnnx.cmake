# semlio::segment_onnx: the optional network segmenter (include/semlio/segment/onnx/:
# OnnxSegmenter runs a user's ONNX range-image model through OpenCV's DNN
# module). Header-only like the rest, but its header includes OpenCV, so it
# gets a target of its own that links opencv_core and opencv_dnn; semlio::semlio
# never needs them. Built when both are found (Debian: libopencv-dnn-dev), or
# never with -DSEMLIO_WITH_ONNX=OFF. Consumers get SEMLIO_HAVE_ONNX=1 defined.
#
# OpenCV's CMake package comes first when installed (find_package(OpenCV)).
# Debian ships it only in libopencv-dev, which pulls in ~240 packages (GUI,
# video, ...); libopencv-dnn-dev alone has the headers and libraries, so
# without the package the two libraries and the include directory are found
# directly. The same search runs in the installed package config
# (semlio_find_opencv_dnn below, installed beside semlioConfig.cmake).
# Sets SEMLIO_OPENCV_DNN_FOUND and the imported target semlio_opencv_dnn
# (OpenCV's own targets when its package is found, else the libraries found by name).
macro(semlio_find_opencv_dnn)
  set(SEMLIO_OPENCV_DNN_FOUND OFF)
  if(NOT TARGET semlio_opencv_dnn)
    find_package(OpenCV QUIET COMPONENTS core dnn)
    if(OpenCV_FOUND)
      add_library(semlio_opencv_dnn INTERFACE IMPORTED)
      target_link_libraries(semlio_opencv_dnn INTERFACE opencv_core opencv_dnn)
      set(SEMLIO_OPENCV_DNN_FOUND ON)
    else()
      find_path(SEMLIO_OPENCV_INCLUDE_DIR opencv2/dnn.hpp PATH_SUFFIXES opencv4)
      find_library(SEMLIO_OPENCV_CORE_LIBRARY opencv_core)
      find_library(SEMLIO_OPENCV_DNN_LIBRARY opencv_dnn)
      if(SEMLIO_OPENCV_INCLUDE_DIR AND SEMLIO_OPENCV_CORE_LIBRARY AND SEMLIO_OPENCV_DNN_LIBRARY)
        add_library(semlio_opencv_dnn INTERFACE IMPORTED)
        # Imported: its include directory is a system one, so OpenCV's own
        # headers never trip our warnings-as-errors.
        set_target_properties(semlio_opencv_dnn PROPERTIES
          INTERFACE_INCLUDE_DIRECTORIES "${SEMLIO_OPENCV_INCLUDE_DIR}"
          INTERFACE_LINK_LIBRARIES "${SEMLIO_OPENCV_DNN_LIBRARY};${SEMLIO_OPENCV_CORE_LIBRARY}")
        set(SEMLIO_OPENCV_DNN_FOUND ON)
      endif()
    endif()
  else()
    set(SEMLIO_OPENCV_DNN_FOUND ON)
  endif()
endmacro()

# The package config includes this file only for the macro above.
if(SEMLIO_ONNX_FIND_ONLY)
  return()
endif()

option(SEMLIO_WITH_ONNX "Build the ONNX segmenter (semlio::segment_onnx) when OpenCV's DNN module is found" ON)
set(SEMLIO_HAVE_ONNX OFF)
if(SEMLIO_WITH_ONNX)
  semlio_find_opencv_dnn()
  if(SEMLIO_OPENCV_DNN_FOUND)
    set(SEMLIO_HAVE_ONNX ON)
    add_library(semlio_segment_onnx INTERFACE)
    add_library(semlio::segment_onnx ALIAS semlio_segment_onnx)
    set_target_properties(semlio_segment_onnx PROPERTIES EXPORT_NAME segment_onnx)
    # The imported target is linked by name: the package config defines it
    # again in the consumer's project (semlio_find_opencv_dnn).
    target_link_libraries(semlio_segment_onnx INTERFACE semlio semlio_opencv_dnn)
    target_compile_definitions(semlio_segment_onnx INTERFACE SEMLIO_HAVE_ONNX=1)
    message(STATUS "semlio: ONNX segmenter (semlio::segment_onnx) enabled")
  else()
    message(STATUS "semlio: ONNX segmenter disabled (needs OpenCV's core and dnn modules: libopencv-dnn-dev)")
  endif()
endif()
