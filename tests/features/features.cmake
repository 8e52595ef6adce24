# Features and search area: preprocessing, rings, LOAM features, PCA, k-d tree, k-best,
# voxel grid (paths relative to tests/).
set(SEMLIO_TESTS_features_features
  features/test_pca.cpp
  features/test_rings.cpp
  features/test_preprocess.cpp
  features/test_loam_features.cpp
  features/test_sensor_profiles.cpp
  features/test_beam_detection.cpp
  features/test_profile_match.cpp
  search/test_kdtree.cpp
  search/test_k_best.cpp
  search/test_voxel_grid.cpp)
