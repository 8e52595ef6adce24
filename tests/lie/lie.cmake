set(SEMLIO_TESTS_lie_lie lie/test_so3.cpp lie/test_se3.cpp)
