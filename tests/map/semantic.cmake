# Global semantic map.
set(SEMLIO_TESTS_map_semantic map/test_semantic_map.cpp)
