# PCD and PLY point-cloud readers/writers (include/semlio/io/pcd.hpp, ply.hpp).
set(SEMLIO_TESTS_io_cloud io/test_pcd.cpp io/test_ply.cpp)
