# Benchmarks of the graph area.
semlio_add_benchmark(bench_pgo graph/bench_pgo.cpp)

# Optional peer: the same problems solved with Ceres (never a dependency of
# the library; built only when libceres-dev is installed).
find_package(Ceres QUIET)
if(Ceres_FOUND)
  semlio_add_benchmark(bench_pgo_ceres graph/bench_pgo_ceres.cpp)
  target_link_libraries(bench_pgo_ceres PRIVATE Ceres::ceres)
endif()
