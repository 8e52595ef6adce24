set(SEMLIO_TESTS_solve_solve solve/test_gauss_newton.cpp solve/test_degeneracy.cpp)
