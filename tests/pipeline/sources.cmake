set(SEMLIO_TESTS_pipeline)
