# ROS message deserialisation without ROS: PointCloud2 / Imu in ROS 1 and CDR
# form, and PointCloud2 -> Scan for every driver's field layout
# (include/semlio/io/pointcloud2.hpp, ros1_msgs.hpp, cdr_msgs.hpp).
set(SEMLIO_TESTS_io_ros io/test_pointcloud2.cpp io/test_ros1_msgs.cpp io/test_cdr_msgs.cpp)
