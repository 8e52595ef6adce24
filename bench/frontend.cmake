# Benchmarks of the frontend area.
