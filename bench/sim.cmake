# Benchmarks of the sim area.
semlio_add_benchmark(bench_raycast sim/bench_raycast.cpp)
