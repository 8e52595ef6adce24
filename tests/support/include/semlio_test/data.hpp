#pragma once
// Paths to the real data bundled in tests/data (see tests/data/README.md).
#include <string>

namespace semlio_test {

/// Absolute path of a file under tests/data.
inline std::string data_path(const std::string& relative) {
  return std::string(SEMLIO_TEST_DATA_DIR) + "/" + relative;
}

}  // namespace semlio_test
