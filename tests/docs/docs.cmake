# The docs' checks (test names "docs: ..."): docs/design.md's policy example
# and the README's library example compile and run, docs/config.md's defaults
# equal the code's, README.md stays short.
# An executable of its own, not an area of semlio_tests: the config check
# reads semlio_kitti's YAML loader (examples/kitti/settings_yaml.hpp), which
# needs yaml-cpp, a dependency of the examples only.
if(NOT SEMLIO_BUILD_EXAMPLES)
  return()
endif()
find_package(yaml-cpp REQUIRED)
set(SEMLIO_TESTS_docs_docs docs/test_design_example.cpp docs/test_readme_example.cpp docs/test_config_doc.cpp
  docs/test_docs.cpp)
add_executable(semlio_tests_docs_docs ${SEMLIO_TESTS_docs_docs})
# One TU: the two examples and the config check include the same pipelines.
set_target_properties(semlio_tests_docs_docs PROPERTIES UNITY_BUILD ON)
target_include_directories(semlio_tests_docs_docs PRIVATE
  "${PROJECT_SOURCE_DIR}/examples/kitti" "${PROJECT_SOURCE_DIR}/examples/common")
target_compile_definitions(semlio_tests_docs_docs PRIVATE SEMLIO_SOURCE_DIR="${PROJECT_SOURCE_DIR}")
target_link_libraries(semlio_tests_docs_docs PRIVATE semlio::semlio semlio_test_support semlio_catch_main yaml-cpp)
semlio_set_warnings(semlio_tests_docs_docs)
catch_discover_tests(semlio_tests_docs_docs TEST_PREFIX "docs: " EXTRA_ARGS --warn NoTests)
