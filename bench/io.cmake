# Benchmarks of the io area: bag containers read + PointCloud2 decoded into
# Scans on the real KITTI scans of tests/data/bags. They need the optional bag
# component (cmake/SemlioBags.cmake).
if(SEMLIO_HAVE_BAGS)
  semlio_add_benchmark(bench_bag_read io/bench_bag_read.cpp)
  target_link_libraries(bench_bag_read PRIVATE semlio::io_bags)
endif()
# The same for MCAP (zstd chunks, CDR): bench/io/bench_mcap_read.cpp.
if(SEMLIO_HAVE_BAGS)
  semlio_add_benchmark(bench_mcap_read io/bench_mcap_read.cpp)
  target_link_libraries(bench_mcap_read PRIVATE semlio::io_bags)
endif()
