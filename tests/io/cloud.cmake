set(SEMLIO_TESTS_io_cloud)
