# Examples of the register area.
find_package(CLI11 REQUIRED)
semlio_add_example(semlio_register register/semlio_register.cpp)
target_link_libraries(semlio_register PRIVATE CLI11::CLI11)
