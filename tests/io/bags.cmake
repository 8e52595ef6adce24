# Bag containers (include/semlio/io/bag/): ROS 1 bags, MCAP, rosbag2 sqlite3,
# tested on files written by the reference implementations (tests/data/bags).
set(SEMLIO_TESTS_io_bags io/test_rosbag1.cpp io/test_mcap.cpp io/test_sqlite_bag.cpp
  io/test_bag_writers.cpp io/test_bz2_limit.cpp)
