set(SEMLIO_TESTS_solve_solve solve/test_gauss_newton.cpp)
