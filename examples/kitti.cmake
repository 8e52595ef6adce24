# Examples of the kitti area.
find_package(CLI11 REQUIRED)
find_package(yaml-cpp REQUIRED)
semlio_add_example(semlio_kitti kitti/semlio_kitti.cpp)
target_include_directories(semlio_kitti PRIVATE "${CMAKE_CURRENT_SOURCE_DIR}/run" "${CMAKE_CURRENT_SOURCE_DIR}/kitti")
target_link_libraries(semlio_kitti PRIVATE CLI11::CLI11 yaml-cpp)
