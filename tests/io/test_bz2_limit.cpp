// bz2 chunks of ROS 1 bags (io/bag/detail/decompress.hpp): a chunk header
// that states far more bytes than its bz2 stream gives costs no allocation of
// the stated size, a stream that would expand beyond the stated size stops
// there, and both are a FormatError; so is a truncated stream. The streams are
// made here with libbz2's own compressor.
#include <catch2/catch.hpp>

#include <bzlib.h>

#include <cstdint>
#include <cstring>
#include <string>
#include <vector>

#include <semlio/core/error.hpp>
#include <semlio/io/bag/detail/decompress.hpp>
#include <semlio/io/bag/rosbag1.hpp>
#include <semlio_test/data.hpp>

namespace test_bz2_limit {  // one namespace per test file: the area compiles as one TU

namespace {

using semlio::io::detail::decompress_bz2;

/// `data` compressed by libbz2 (block size 9).
std::vector<std::uint8_t> bz2(const std::vector<std::uint8_t>& data) {
  std::vector<std::uint8_t> out(data.size() + data.size() / 100 + 600);  // bzlib's documented worst case
  auto n = static_cast<unsigned int>(out.size());
  char none = 0;  // bzlib refuses a null source even for 0 bytes
  char* source = data.empty() ? &none : const_cast<char*>(reinterpret_cast<const char*>(data.data()));
  const int rc = BZ2_bzBuffToBuffCompress(reinterpret_cast<char*>(out.data()), &n, source,
                                          static_cast<unsigned int>(data.size()), 9, 0, 0);
  REQUIRE(rc == BZ_OK);
  out.resize(n);
  return out;
}

/// `n` bytes that do not compress (a 32-bit LCG's high bytes).
std::vector<std::uint8_t> noise(std::size_t n) {
  std::vector<std::uint8_t> v(n);
  std::uint32_t x = 12345;
  for (auto& b : v) {
    x = x * 1664525U + 1013904223U;
    b = static_cast<std::uint8_t>(x >> 24);
  }
  return v;
}

constexpr std::size_t kMiB = std::size_t{1} << 20;

}  // namespace

TEST_CASE("bz2 chunk: a stated size far beyond what the stream holds allocates only what the stream gives",
          "[io][rosbag1][bz2]") {
  const std::vector<std::uint8_t> data = noise(100000);
  const std::vector<std::uint8_t> in = bz2(data);
  REQUIRE(in.size() > 100000);  // incompressible: 100 kB of bz2 may expand to 2 GiB by the format's bound
  std::vector<std::uint8_t> out;
  // 1.5 GiB stated, 100 000 bytes in the stream: the old code resized the
  // output to the stated 1.5 GiB (and zero-filled it) before decompressing.
  const std::uint64_t stated = std::uint64_t{3} << 29;
  CHECK_THROWS_WITH(decompress_bz2(in.data(), in.size(), stated, out, "bag chunk 7"),
                    Catch::Contains("bag chunk 7") && Catch::Contains("decompresses to 100000 bytes") &&
                        Catch::Contains(std::to_string(stated)));
  CHECK(out.capacity() < 2 * kMiB);
}

TEST_CASE("bz2 chunk: a tiny stream stating up to the 2 GiB limit is refused before any allocation",
          "[io][rosbag1][bz2]") {
  const std::vector<std::uint8_t> in = bz2(std::vector<std::uint8_t>(10, 'a'));
  REQUIRE(in.size() < 100);
  std::vector<std::uint8_t> out;
  // 100 bytes of bz2 give at most 100 / 10 blocks * 46 620 000 bytes.
  CHECK_THROWS_WITH(decompress_bz2(in.data(), in.size(), std::uint64_t{1} << 31, out, "chunk"),
                    Catch::Contains("bytes of bz2 can hold"));
  CHECK(out.capacity() == 0);
  // Beyond the 2 GiB limit: refused whatever the stream.
  CHECK_THROWS_WITH(decompress_bz2(in.data(), in.size(), (std::uint64_t{1} << 31) + 1, out, "chunk"),
                    Catch::Contains("2 GiB limit"));
}

TEST_CASE("bz2 chunk: a stream expanding beyond the stated size stops at it", "[io][rosbag1][bz2]") {
  // 40 MB of zeros compress to a few dozen bytes (a bz2 bomb in miniature).
  const std::vector<std::uint8_t> zeros(40 * kMiB, 0);
  const std::vector<std::uint8_t> in = bz2(zeros);
  REQUIRE(in.size() < 1000);
  std::vector<std::uint8_t> out;
  CHECK_THROWS_WITH(decompress_bz2(in.data(), in.size(), 4096, out, "chunk"),
                    Catch::Contains("more than the 4096 bytes the header states"));
  CHECK(out.capacity() <= 4096);
  // One byte short of the real size: still refused, never written past.
  CHECK_THROWS_AS(decompress_bz2(in.data(), in.size(), zeros.size() - 1, out, "chunk"), semlio::FormatError);
  CHECK(out.size() <= zeros.size() - 1);
  // The exact size: the 40 MB come back (the output grew from 64 KiB).
  decompress_bz2(in.data(), in.size(), zeros.size(), out, "chunk");
  CHECK(out == zeros);
}

TEST_CASE("bz2 chunk: exact sizes decode bit-exact, truncated and corrupt streams are FormatErrors",
          "[io][rosbag1][bz2]") {
  // Noise followed by a compressible run: the output buffer grows past its
  // first guess (4x the input) several times.
  std::vector<std::uint8_t> data = noise(3000);
  data.resize(3 * kMiB, 7);
  const std::vector<std::uint8_t> in = bz2(data);
  REQUIRE(4 * in.size() < data.size() / 4);
  std::vector<std::uint8_t> out;
  decompress_bz2(in.data(), in.size(), data.size(), out, "chunk");
  CHECK(out == data);
  // Empty payload: a 14-byte stream of no blocks.
  const std::vector<std::uint8_t> empty = bz2({});
  decompress_bz2(empty.data(), empty.size(), 0, out, "chunk");
  CHECK(out.empty());
  // Truncated (the end-of-stream marker cut off).
  CHECK_THROWS_WITH(decompress_bz2(in.data(), in.size() - 5, data.size(), out, "chunk"),
                    Catch::Contains("chunk") && Catch::Contains("bz2"));
  // Corrupt: a byte in the middle of the block flipped (the CRC or the
  // Huffman data catches it).
  std::vector<std::uint8_t> bad = in;
  bad[bad.size() / 2] ^= 0x55;
  CHECK_THROWS_AS(decompress_bz2(bad.data(), bad.size(), data.size(), out, "chunk"), semlio::FormatError);
}

TEST_CASE("bz2 chunk: a ROS 1 bag whose bz2 chunk header lies about its size is a FormatError naming the chunk",
          "[io][rosbag1][bz2]") {
  const std::string good = semlio_test::read_bytes(semlio_test::data_path("bags/quirks_bz2.bag"));
  // Chunk record headers hold the field `size=<uint32 LE>` (4-byte field
  // length 9); state 2^31 - 1 bytes in every one.
  const std::string field("\x09\x00\x00\x00size=", 9);
  std::string bad = good;
  std::size_t patched = 0;
  for (std::size_t at = bad.find(field); at != std::string::npos; at = bad.find(field, at + 1)) {
    const std::uint32_t lie = 0x7FFFFFFFU;
    std::memcpy(&bad[at + field.size()], &lie, 4);
    ++patched;
  }
  REQUIRE(patched >= 1);
  const auto read_all = [](const std::string& bytes) {
    semlio::io::RosBag1Reader r = semlio::io::RosBag1Reader::from_bytes(bytes, "lying.bag");
    semlio::io::BagMessage m;
    std::size_t n = 0;
    while (r.next(m)) ++n;
    return n;
  };
  CHECK(read_all(good) >= 5);
  CHECK_THROWS_AS(read_all(bad), semlio::FormatError);
  CHECK_THROWS_WITH(read_all(bad), Catch::Contains("lying.bag") && Catch::Contains("bz2"));
}

}  // namespace test_bz2_limit
