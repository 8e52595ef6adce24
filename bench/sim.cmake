# Benchmarks of the sim area.
