set(SEMLIO_TESTS_core_core core/test_labels.cpp core/test_scan.cpp core/test_fast_math.cpp core/test_buffers.cpp core/test_radix_sort.cpp core/test_stopwatch.cpp)
