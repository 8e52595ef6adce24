# OnnxSegmenter (include/semlio/segment/onnx/): the tiny committed model of
# tests/data/onnx (scripts/make_onnx_fixture.py) checks projection, channel
# order, normalisation, class mapping and back-projection exactly. Needs the
# optional component (cmake/SemlioOnnx.cmake); the model card YAML reader
# (examples/common/model_card_yaml.hpp) is tested too when yaml-cpp is found.
set(SEMLIO_TESTS_segment_onnx segment/test_onnx_segmenter.cpp)
set(SEMLIO_TESTS_segment_onnx_LIBS semlio::segment_onnx)
if(yaml-cpp_FOUND)
  if(NOT TARGET semlio_test_onnx_yaml)
    add_library(semlio_test_onnx_yaml INTERFACE)
    target_compile_definitions(semlio_test_onnx_yaml INTERFACE SEMLIO_TEST_ONNX_YAML)
    target_link_libraries(semlio_test_onnx_yaml INTERFACE yaml-cpp)
  endif()
  list(APPEND SEMLIO_TESTS_segment_onnx_LIBS semlio_test_onnx_yaml)
  set(SEMLIO_TESTS_segment_onnx_INCLUDES "${PROJECT_SOURCE_DIR}/examples/common")
endif()
