# Benchmarks of the lie area.
