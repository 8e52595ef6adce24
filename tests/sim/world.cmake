set(SEMLIO_TESTS_sim_world)
