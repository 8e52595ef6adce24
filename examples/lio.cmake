# Examples of the lio area (lidar-inertial odometry).
find_package(CLI11 REQUIRED)
semlio_add_example(semlio_lio lio/semlio_lio.cpp)
target_link_libraries(semlio_lio PRIVATE CLI11::CLI11)
