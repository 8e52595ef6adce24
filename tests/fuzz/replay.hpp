#pragma once
// Replays every committed input of a harness -- tests/fuzz/corpus/<name>/ and
// tests/fuzz/crashes/<name>/ -- through the same body libFuzzer runs. A trap
// (invariant violated) or a crash ends the test executable; an exception other
// than semlio::Error fails the test case.
#include <catch2/catch.hpp>

#include <algorithm>
#include <cstdint>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

namespace semlio_fuzz {

/// tests/fuzz in the source tree: the folder of this header (CMake compiles
/// sources by absolute path, so __FILE__ is absolute).
inline std::filesystem::path fuzz_dir() { return std::filesystem::path(__FILE__).parent_path(); }

/// Files of tests/fuzz/<kind>/<name>/, sorted (empty when the folder is absent).
inline std::vector<std::filesystem::path> inputs(const std::string& kind, const std::string& name) {
  std::vector<std::filesystem::path> out;
  const std::filesystem::path dir = fuzz_dir() / kind / name;
  std::error_code ec;
  if (!std::filesystem::is_directory(dir, ec)) return out;
  for (const auto& e : std::filesystem::directory_iterator(dir)) {
    if (e.is_regular_file() && e.path().filename().string().front() != '.') out.push_back(e.path());
  }
  std::sort(out.begin(), out.end());
  return out;
}

/// Runs every corpus and crash input of harness `name` through `body`;
/// requires a non-empty seed corpus.
template <typename Body>
void replay(const std::string& name, Body body) {
  const auto corpus = inputs("corpus", name);
  INFO("harness " << name << ": " << corpus.size() << " corpus files in " << fuzz_dir().string());
  REQUIRE(!corpus.empty());
  std::vector<std::filesystem::path> all = corpus;
  for (const auto& p : inputs("crashes", name)) all.push_back(p);
  for (const auto& p : all) {
    std::ifstream in(p, std::ios::binary);
    std::ostringstream ss;
    ss << in.rdbuf();
    const std::string bytes = ss.str();
    INFO("input " << p.string() << " (" << bytes.size() << " bytes)");
    CHECK(body(reinterpret_cast<const std::uint8_t*>(bytes.data()), bytes.size()) == 0);
  }
}

}  // namespace semlio_fuzz
