# Examples of the sim area.
semlio_add_example(semlio_simulate sim/semlio_simulate.cpp)
