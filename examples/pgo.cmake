# Examples of the pgo area.
semlio_add_example(semlio_pgo pgo/semlio_pgo.cpp)
