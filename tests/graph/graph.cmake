set(SEMLIO_TESTS_graph_graph graph/test_pose_graph.cpp graph/test_keyframe_inertial_graph.cpp io/test_g2o.cpp)
