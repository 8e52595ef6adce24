# Local map, label agreement, associators (Algorithm 1) and residuals (eq. 8-12).
set(SEMLIO_TESTS_associate_associate
  associate/test_associators.cpp
  map/test_label_agreement.cpp
  map/test_local_map.cpp
  residual/test_residuals.cpp)
