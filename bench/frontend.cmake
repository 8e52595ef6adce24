# Benchmarks of the frontend area.
semlio_add_benchmark(bench_features frontend/bench_features.cpp)
