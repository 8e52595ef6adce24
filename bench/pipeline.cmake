# Benchmarks of the pipeline area.
# Front-end association kernel, local map build and residual accumulation
# (associate/, map/, residual/); run with scripts/bench_association.sh.
semlio_add_benchmark(bench_association frontend/bench_association.cpp)
