# Examples of the io area. semlio_convert's dataset mode reads every input
# semlio_run reads (examples/run/ sources; bags with semlio::io_bags).
find_package(CLI11 REQUIRED)
semlio_add_example(semlio_convert io/semlio_convert.cpp)
target_include_directories(semlio_convert PRIVATE "${CMAKE_CURRENT_SOURCE_DIR}/run")
target_link_libraries(semlio_convert PRIVATE CLI11::CLI11)
if(SEMLIO_HAVE_BAGS)
  target_link_libraries(semlio_convert PRIVATE semlio::io_bags)
  target_compile_definitions(semlio_convert PRIVATE SEMLIO_HAVE_BAGS)
endif()
