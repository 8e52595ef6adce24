set(SEMLIO_TESTS_graph)
