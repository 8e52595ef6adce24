# Examples of the eval area.
semlio_add_example(semlio_eval eval/semlio_eval.cpp)
