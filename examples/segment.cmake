# Examples of the segment area.
semlio_add_example(semlio_segment_eval segment/semlio_segment_eval.cpp)
