set(SEMLIO_TESTS_segment_segment segment/test_geometric_segmenter.cpp segment/test_range_projection.cpp
    segment/test_segment_eval.cpp)
# test_segment_eval.cpp tests semlio_segment_eval's measurement header.
set(SEMLIO_TESTS_segment_segment_INCLUDES "${PROJECT_SOURCE_DIR}/examples/segment")
# semlio_segment_eval --sequence on the real labelled scans (output format).
if(SEMLIO_BUILD_EXAMPLES)
  add_test(NAME segment_eval_real_kitti
           COMMAND ${CMAKE_COMMAND} "-DTOOL=$<TARGET_FILE:semlio_segment_eval>"
                   "-DDATA_DIR=${CMAKE_CURRENT_SOURCE_DIR}/data" -P "${CMAKE_CURRENT_SOURCE_DIR}/segment/segment_eval_check.cmake")
  set_tests_properties(segment_eval_real_kitti PROPERTIES LABELS "segment;examples" TIMEOUT 300)
endif()
