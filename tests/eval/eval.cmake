set(SEMLIO_TESTS_eval_eval)
