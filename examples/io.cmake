# Examples of the io area.
semlio_add_example(semlio_convert io/semlio_convert.cpp)
