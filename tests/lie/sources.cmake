set(SEMLIO_TESTS_lie lie/test_se3_smoke.cpp)
