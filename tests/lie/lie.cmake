set(SEMLIO_TESTS_lie_lie lie/test_se3_smoke.cpp)
