// Preprocessed only (see CMakeLists.txt): every header of the umbrella is installed.
#include <semlio/semlio.hpp>
