# Global semantic map.
set(SEMLIO_TESTS_map_semantic)
