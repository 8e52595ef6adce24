// JsonWriter (examples/common/json_writer.hpp): numbers read back as the
// same double -- epoch stamps keep their fraction -- and non-finite values
// become null and are counted, so report.json is always valid JSON.
#include <catch2/catch.hpp>

#include <cstdlib>
#include <limits>
#include <sstream>
#include <string>

#include "json_writer.hpp"

namespace test_json_writer {

TEST_CASE("JsonWriter: numbers read back exactly, non-finite ones are null", "[examples]") {
  std::ostringstream os;
  semlio_examples::JsonWriter j(os);
  const double stamp = 1317357625.1;  // a KITTI raw header stamp [s]
  const double small = 0.0692403422647395;
  j.begin_array();
  j.value(stamp).value(small).value(0.1).value(std::numeric_limits<double>::quiet_NaN());
  j.value(std::numeric_limits<double>::infinity());
  j.end_array();
  CHECK(os.str() == "[1317357625.1,0.0692403422647395,0.1,null,null]");
  CHECK(j.non_finite_count() == 2);
  // Each number parses back to the double that was written.
  const std::string text = os.str();
  CHECK(std::strtod(text.c_str() + 1, nullptr) == stamp);
  CHECK(std::strtod(text.c_str() + text.find(',') + 1, nullptr) == small);
}

}  // namespace test_json_writer
