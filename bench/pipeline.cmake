# Benchmarks of the pipeline area.
# Front-end association kernel, local map build and residual accumulation
# (associate/, map/, residual/); run with scripts/bench_association.sh.
semlio_add_benchmark(bench_association frontend/bench_association.cpp)
# Per-frame wall and thread-CPU time of the whole odometry on a sequence;
# run with scripts/frame_time.sh.
semlio_add_benchmark(bench_frame_time pipeline/bench_frame_time.cpp)
