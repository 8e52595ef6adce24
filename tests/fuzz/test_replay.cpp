// Replays the committed fuzz corpus and crash inputs of every reader harness
// (tests/fuzz/harnesses.hpp) in the regular test build.
#include <catch2/catch.hpp>

#include <string>

#include "harnesses.hpp"
#include "replay.hpp"

namespace test_replay {

TEST_CASE("fuzz replay: every corpus and crash input of the reader harnesses", "[fuzz]") {
  for (const semlio_fuzz::Harness& h : semlio_fuzz::kHarnesses) {
    SECTION(h.name) { semlio_fuzz::replay(h.name, h.body); }
  }
}

}  // namespace test_replay
