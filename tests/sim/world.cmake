set(SEMLIO_TESTS_sim_world
  sim/test_geometry.cpp
  sim/test_bvh.cpp
  sim/test_lidar.cpp
  sim/test_world.cpp
  sim/test_simulator.cpp
  sim/test_sim_vs_kitti.cpp
  sim/test_kitti_writer.cpp)
