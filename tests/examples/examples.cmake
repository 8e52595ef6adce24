# The tools' own headers (examples/common): their YAML parsers need yaml-cpp,
# as the tools do (tests/CMakeLists.txt adds this area when yaml-cpp is found).
set(SEMLIO_TESTS_examples_examples
  examples/test_json_writer.cpp
  examples/test_sensor_yaml.cpp)
set(SEMLIO_TESTS_examples_examples_LIBS yaml-cpp)
set(SEMLIO_TESTS_examples_examples_INCLUDES ${PROJECT_SOURCE_DIR}/examples/common)
