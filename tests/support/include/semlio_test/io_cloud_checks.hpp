#pragma once
// Catch2 checks shared by the PCD/PLY reader tests.
#include <catch2/catch.hpp>

#include <string>

namespace semlio_test {

/// Requires that f() throws exactly an E whose message names `path` and
/// contains `fragment` (the bad value or the numbers involved).
template <typename E, typename F>
void require_error(F&& f, const std::string& path, const std::string& fragment) {
  bool thrown = false;
  try {
    f();
  } catch (const E& e) {
    thrown = true;
    const std::string msg = e.what();
    INFO("message: " << msg);
    CHECK(msg.find(path) != std::string::npos);
    CHECK(msg.find(fragment) != std::string::npos);
  }
  CHECK(thrown);
}

}  // namespace semlio_test
