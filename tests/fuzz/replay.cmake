# Fuzz harnesses (tests/fuzz/harnesses.hpp) replayed in the regular build:
# every file of tests/fuzz/corpus/<reader>/ and tests/fuzz/crashes/<reader>/
# goes through the same body libFuzzer runs (scripts/fuzz.sh).
# The inputs are found next to replay.hpp (tests/fuzz), so the area needs no
# per-source definitions (it compiles as one unity TU).
set(SEMLIO_TESTS_fuzz_replay fuzz/test_replay.cpp)

# The YAML settings harness and the --config loader's tests need yaml-cpp and
# the examples' headers: an executable of its own, as tests/docs does.
if(SEMLIO_BUILD_EXAMPLES)
  find_package(yaml-cpp REQUIRED)
  add_executable(semlio_tests_fuzz_yaml fuzz/test_settings_yaml.cpp)
  target_include_directories(semlio_tests_fuzz_yaml PRIVATE
    "${PROJECT_SOURCE_DIR}/examples/kitti" "${PROJECT_SOURCE_DIR}/examples/common")
  target_link_libraries(semlio_tests_fuzz_yaml PRIVATE semlio::semlio semlio_catch_main yaml-cpp)
  semlio_set_warnings(semlio_tests_fuzz_yaml)
  catch_discover_tests(semlio_tests_fuzz_yaml TEST_PREFIX "fuzz yaml: " EXTRA_ARGS --warn NoTests)
endif()

# The bag container harnesses (harnesses_bags.hpp) need the bag libraries:
# their replay is an executable of its own, built when they were found.
if(SEMLIO_HAVE_BAGS)
  add_executable(semlio_tests_fuzz_bags fuzz/test_replay_bags.cpp)
  target_link_libraries(semlio_tests_fuzz_bags PRIVATE semlio::semlio semlio::io_bags semlio_catch_main)
  semlio_set_warnings(semlio_tests_fuzz_bags)
  catch_discover_tests(semlio_tests_fuzz_bags TEST_PREFIX "fuzz bags: " EXTRA_ARGS --warn NoTests)
endif()

# libFuzzer: one executable, semlio_fuzz, holding every harness body (the
# environment variable SEMLIO_FUZZ_HARNESS picks one per run); clang only,
# -DSEMLIO_FUZZ=ON (scripts/fuzz.sh configures its own build directory so).
option(SEMLIO_FUZZ "Build the libFuzzer harnesses (clang: -fsanitize=fuzzer,address,undefined)" OFF)
if(SEMLIO_FUZZ)
  find_package(yaml-cpp REQUIRED)
  add_executable(semlio_fuzz fuzz/fuzz_main.cpp)
  target_compile_options(semlio_fuzz PRIVATE -fsanitize=fuzzer,address,undefined -fno-sanitize-recover=undefined -g -O1)
  target_link_options(semlio_fuzz PRIVATE -fsanitize=fuzzer,address,undefined)
  target_include_directories(semlio_fuzz PRIVATE
    "${PROJECT_SOURCE_DIR}/examples/kitti" "${PROJECT_SOURCE_DIR}/examples/common")
  target_link_libraries(semlio_fuzz PRIVATE semlio::semlio yaml-cpp)
  # With the bag libraries (-DSEMLIO_WITH_BAGS=ON and found) the bag
  # container harnesses join: SEMLIO_FUZZ_BAGS compiles harnesses_bags.hpp in.
  if(SEMLIO_HAVE_BAGS)
    target_link_libraries(semlio_fuzz PRIVATE semlio::io_bags)
    target_compile_definitions(semlio_fuzz PRIVATE SEMLIO_FUZZ_BAGS=1)
  endif()
endif()
