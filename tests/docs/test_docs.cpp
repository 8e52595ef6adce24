// The docs keep their promises: design.md shows exactly the example code that
// test_design_example.cpp compiles and runs, README.md stays short and carries
// the generated results block, and docs/results_quick.md is the generated page.
#include <catch2/catch.hpp>

#include <fstream>
#include <sstream>
#include <string>

namespace test_docs {

namespace {

std::string read(const std::string& relative) {
  std::ifstream in(std::string(SEMLIO_SOURCE_DIR) + "/" + relative);
  INFO(relative);
  REQUIRE(in.good());
  std::stringstream ss;
  ss << in.rdbuf();
  return ss.str();
}

// The text strictly between the line holding `begin` and the line holding `end`.
std::string between(const std::string& text, const std::string& begin, const std::string& end) {
  const auto b = text.find(begin);
  REQUIRE(b != std::string::npos);
  const auto start = text.find('\n', b) + 1;
  const auto e = text.find(end, start);
  REQUIRE(e != std::string::npos);
  const auto stop = text.rfind('\n', e) + 1;
  return text.substr(start, stop - start);
}

}  // namespace

TEST_CASE("docs/design.md shows the example test_design_example.cpp compiles", "[docs]") {
  const std::string code =
      between(read("tests/docs/test_design_example.cpp"), "// [design-example-begin]", "// [design-example-end]");
  const std::string doc = between(read("docs/design.md"), "<!-- design-example-begin -->", "<!-- design-example-end -->");
  CHECK(code.size() > 1000);  // the markers enclose the whole example
  CHECK(doc == "```cpp\n" + code + "```\n");
}

TEST_CASE("README.md shows the library example test_readme_example.cpp compiles", "[docs]") {
  const std::string code =
      between(read("tests/docs/test_readme_example.cpp"), "// [readme-example-begin]", "// [readme-example-end]");
  const std::string readme = read("README.md");
  CHECK(code.size() > 500);
  CHECK(readme.find("```cpp\n" + code + "```\n") != std::string::npos);
}

TEST_CASE("README.md stays short and docs/results_quick.md is a generated page", "[docs]") {
  std::ifstream readme(std::string(SEMLIO_SOURCE_DIR) + "/README.md");
  REQUIRE(readme.good());
  int lines = 0;
  std::string line;
  bool results_block = false;
  while (std::getline(readme, line)) {
    ++lines;
    if (line.find("<!-- results:begin") != std::string::npos) results_block = true;
  }
  CHECK(lines <= 400);
  CHECK(results_block);  // scripts/reproduce.sh writes the summary table there
  std::ifstream quick(std::string(SEMLIO_SOURCE_DIR) + "/docs/results_quick.md");
  REQUIRE(quick.good());
  std::getline(quick, line);
  CHECK(line == "# Results, quick run");
}

}  // namespace test_docs
