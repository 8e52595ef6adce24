# Benchmarks of the frontend area.
semlio_add_benchmark(bench_features frontend/bench_features.cpp)
# One Gauss-Newton iteration, residual accumulation and search-structure builds
# on the real KITTI pair (run with scripts/bench_association.sh).
semlio_add_benchmark(bench_gauss_newton frontend/bench_gauss_newton.cpp)
