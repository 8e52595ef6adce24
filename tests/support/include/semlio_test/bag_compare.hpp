#pragma once
// Catch2 checks shared by the bag reader tests: two readers of the same bag
// (e.g. its path and from_bytes) list the same topics and return the same
// messages in the same order.
#include <catch2/catch.hpp>

#include <cstddef>

#include <semlio/io/bag/message.hpp>

namespace semlio_test {

/// Checks topic names and counts, then every message (topic, log time,
/// bytes) of `a` against `b`, and that `b` ends with `a`. Returns the number
/// of messages read from `a`.
template <typename ReaderA, typename ReaderB>
std::size_t check_same_bag(ReaderA& a, ReaderB& b) {
  REQUIRE(b.topics().size() == a.topics().size());
  for (std::size_t i = 0; i < a.topics().size(); ++i) {
    CHECK(b.topics()[i].name == a.topics()[i].name);
    CHECK(b.topics()[i].message_count == a.topics()[i].message_count);
  }
  semlio::io::BagMessage ma;
  semlio::io::BagMessage mb;
  std::size_t n = 0;
  while (a.next(ma)) {
    REQUIRE(b.next(mb));
    CHECK(mb.topic == ma.topic);
    CHECK(mb.log_time_ns == ma.log_time_ns);
    CHECK(mb.data == ma.data);
    ++n;
  }
  CHECK(!b.next(mb));
  return n;
}

}  // namespace semlio_test
