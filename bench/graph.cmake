# Benchmarks of the graph area.
