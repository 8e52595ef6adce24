#pragma once
/// \file
/// One-shot decompression of a bag chunk whose uncompressed size the
/// container states (ROS 1 bag chunk header `size`, MCAP Chunk
/// `uncompressed_size`): bz2, LZ4 frame format and Zstandard. Part of the
/// optional semlio::io_bags component: needs libbz2, liblz4 and libzstd.
/// Every failure, including output that is longer or shorter than stated,
/// throws FormatError naming `what` (the file and the chunk's offset).

#include <bzlib.h>
#include <lz4.h>
#include <lz4frame.h>
#include <zstd.h>

#include <algorithm>
#include <array>
#include <bit>
#include <cstddef>
#include <cstdint>
#include <cstring>
#include <limits>
#include <memory>
#include <string>
#include <vector>

#include <semlio/core/error.hpp>

namespace semlio::io::detail {

/// Upper bound on one decompressed chunk [bytes]: a stated size above it is a
/// lie or an attack, not a chunk (rosbag and MCAP writers use 768 KiB - 4 MiB
/// chunks; a single 128-beam cloud is under 16 MiB).
inline constexpr std::size_t kMaxChunkBytes = std::size_t{1} << 31;

/// Rejects a stated uncompressed size above kMaxChunkBytes.
inline void check_chunk_size(std::uint64_t uncompressed_size, const std::string& what) {
  if (uncompressed_size > kMaxChunkBytes) {
    throw FormatError(what + ": chunk states " + std::to_string(uncompressed_size) +
                      " uncompressed bytes (more than the 2 GiB limit)");
  }
}

/// Largest expansion of an LZ4 frame: a match length grows by 255 per extra
/// byte, so no frame decompresses to more than 255 times its size (plus a
/// block's worth for the headers of tiny frames).
inline constexpr std::uint64_t kMaxLz4Ratio = 255;
/// Largest expansion of a zstd frame: an RLE block turns 4 bytes (3-byte
/// header + the byte) into at most 128 KiB.
inline constexpr std::uint64_t kMaxZstdRatio = 32768;

/// Rejects a stated uncompressed size that `in_size` compressed bytes of a
/// codec with expansion at most `max_ratio` cannot produce: a lie in a tiny
/// file must cost a FormatError, not an allocation (and zero-fill) of up to
/// kMaxChunkBytes.
inline void check_expansion(std::uint64_t in_size, std::uint64_t uncompressed_size, std::uint64_t max_ratio,
                            const char* codec, const std::string& what) {
  constexpr std::uint64_t kSlack = std::uint64_t{1} << 17;  // one 128 KiB block
  // in_size <= kMaxChunkBytes (2^31) for the callers' inputs: no overflow.
  if (in_size <= kMaxChunkBytes && uncompressed_size > in_size * max_ratio + kSlack) {
    throw FormatError(what + ": chunk states " + std::to_string(uncompressed_size) + " uncompressed bytes, more than " +
                      std::to_string(in_size) + " bytes of " + codec + " can hold");
  }
}

/// Largest expansion of a bz2 stream: a block's Burrows-Wheeler data holds at
/// most 900 000 bytes, whose run-length coding gives back at most 259 bytes
/// per 5 (a run of 4 plus a count of 255), 46 620 000 bytes; and every block
/// costs at least its 6-byte magic and 4-byte CRC, so 10 compressed bytes
/// never give more than 46 620 000.
inline constexpr std::uint64_t kMaxBz2Ratio = 4662000;

/// bz2 stream `in` into exactly `uncompressed_size` bytes of `out`. The
/// output grows with what the stream actually produces (never beyond the
/// stated size), so a chunk header that lies about its size costs no
/// allocation of that size, and a stream that would expand beyond it stops
/// there: both are a FormatError.
inline void decompress_bz2(const std::uint8_t* in, std::size_t in_size, std::uint64_t uncompressed_size,
                           std::vector<std::uint8_t>& out, const std::string& what) {
  check_chunk_size(uncompressed_size, what);
  check_expansion(in_size, uncompressed_size, kMaxBz2Ratio, "bz2", what);
  if (in_size > std::numeric_limits<unsigned int>::max()) throw FormatError(what + ": bz2 chunk too large");
  const auto total = static_cast<std::size_t>(uncompressed_size);  // <= kMaxChunkBytes (2^31)
  bz_stream strm{};
  if (BZ2_bzDecompressInit(&strm, 0, 0) != BZ_OK) throw FormatError(what + ": cannot start bz2 decompression");
  const std::unique_ptr<bz_stream, int (*)(bz_stream*)> end(&strm, &BZ2_bzDecompressEnd);
  // bzlib takes non-const pointers but does not write through next_in.
  strm.next_in = const_cast<char*>(reinterpret_cast<const char*>(in));
  strm.avail_in = static_cast<unsigned int>(in_size);
  // First guess: 4x the input (point clouds compress 2-3x), then doubling.
  std::size_t capacity = std::min(total, std::max<std::size_t>(std::size_t{1} << 16, 4 * in_size));
  out.clear();
  out.resize(capacity);
  std::size_t produced = 0;
  for (;;) {
    strm.next_out = reinterpret_cast<char*>(out.data() + produced);
    strm.avail_out = static_cast<unsigned int>(capacity - produced);  // <= 2^31
    const unsigned int in_before = strm.avail_in;
    const unsigned int out_before = strm.avail_out;
    const int rc = BZ2_bzDecompress(&strm);
    produced += out_before - strm.avail_out;
    if (rc == BZ_STREAM_END) break;
    if (rc != BZ_OK) throw FormatError(what + ": bz2 data is corrupt (bzlib error " + std::to_string(rc) + ")");
    if (strm.avail_in == in_before && strm.avail_out == out_before) {
      // No progress: the input is used up before the end-of-stream marker,
      // or the output is full and the stream has more.
      if (produced == total) {
        throw FormatError(what + ": bz2 chunk decompresses to more than the " + std::to_string(total) +
                          " bytes the header states");
      }
      throw FormatError(what + ": bz2 data ends before its end-of-stream marker after " + std::to_string(produced) +
                        " bytes (truncated?)");
    }
    if (produced == capacity && capacity < total) {
      capacity = std::min(total, 2 * capacity);
      out.resize(capacity);
    }
  }
  if (produced != total) {
    throw FormatError(what + ": bz2 chunk decompresses to " + std::to_string(produced) + " bytes, header says " +
                      std::to_string(uncompressed_size));
  }
}

/// XXH32 of n bytes (seed 0): the LZ4 frame's content checksum. liblz4's own
/// copy is auto-vectorised by GCC into an SSE2 loop that emulates the 32-bit
/// multiplies with shifts and runs at a fraction of the scalar speed (~20 % of
/// reading a KITTI lz4 bag); the empty asm statements keep the four lanes
/// scalar, as xxhash.h's XXH_COMPILER_GUARD does.
inline std::uint32_t xxh32(const std::uint8_t* p, std::size_t n) {
  static_assert(std::endian::native == std::endian::little, "xxh32 reads little-endian words");
  constexpr std::uint32_t kP1 = 0x9E3779B1U;
  constexpr std::uint32_t kP2 = 0x85EBCA77U;
  constexpr std::uint32_t kP3 = 0xC2B2AE3DU;
  constexpr std::uint32_t kP4 = 0x27D4EB2FU;
  constexpr std::uint32_t kP5 = 0x165667B1U;
  const auto word = [](const std::uint8_t* q) {
    std::uint32_t v = 0;
    std::memcpy(&v, q, 4);
    return v;
  };
  const auto round = [&](std::uint32_t acc, std::uint32_t input) {
    acc += input * kP2;
    acc = std::rotl(acc, 13) * kP1;
#if defined(__GNUC__) || defined(__clang__)
    __asm__("" : "+r"(acc));
#endif
    return acc;
  };
  const std::size_t len = n;
  std::uint32_t h = 0;
  if (n >= 16) {
    std::uint32_t v1 = kP1 + kP2;
    std::uint32_t v2 = kP2;
    std::uint32_t v3 = 0;
    std::uint32_t v4 = 0U - kP1;
    while (n >= 16) {
      v1 = round(v1, word(p));
      v2 = round(v2, word(p + 4));
      v3 = round(v3, word(p + 8));
      v4 = round(v4, word(p + 12));
      p += 16;
      n -= 16;
    }
    h = std::rotl(v1, 1) + std::rotl(v2, 7) + std::rotl(v3, 12) + std::rotl(v4, 18);
  } else {
    h = kP5;
  }
  h += static_cast<std::uint32_t>(len);
  for (; n >= 4; n -= 4, p += 4) h = std::rotl(h + word(p) * kP3, 17) * kP4;
  for (; n > 0; --n, ++p) h = std::rotl(h + *p * kP5, 11) * kP1;
  h ^= h >> 15;
  h *= kP2;
  h ^= h >> 13;
  h *= kP3;
  h ^= h >> 16;
  return h;
}

/// LZ4 frame (LZ4F, what roslz4 and MCAP write) into exactly
/// `uncompressed_size` bytes of `out`. A content checksum in the frame is
/// always verified: by xxh32() above when liblz4 can be told to skip its own
/// (>= 1.9.4) and the frame has no block checksums, else by liblz4.
inline void decompress_lz4_frame(const std::uint8_t* in, std::size_t in_size, std::uint64_t uncompressed_size,
                                 std::vector<std::uint8_t>& out, const std::string& what) {
  check_chunk_size(uncompressed_size, what);
  check_expansion(in_size, uncompressed_size, kMaxLz4Ratio, "LZ4", what);
  out.resize(static_cast<std::size_t>(uncompressed_size));
  LZ4F_dctx* raw = nullptr;
  if (LZ4F_isError(LZ4F_createDecompressionContext(&raw, LZ4F_VERSION))) {
    throw FormatError(what + ": cannot create an LZ4 decompression context");
  }
  const std::unique_ptr<LZ4F_dctx, decltype(&LZ4F_freeDecompressionContext)> ctx(raw, &LZ4F_freeDecompressionContext);
  // Frame descriptor: magic 0x184D2204, then FLG (bit 4 block checksums, bit 2 content checksum).
  constexpr std::array<std::uint8_t, 4> kLz4Magic = {0x04, 0x22, 0x4D, 0x18};
  const bool framed = in_size >= 5 && std::memcmp(in, kLz4Magic.data(), 4) == 0;
  const bool content_checksum = framed && (in[4] & 0x04U) != 0;
  const bool block_checksums = framed && (in[4] & 0x10U) != 0;
  LZ4F_decompressOptions_t options{};
  options.stableDst = 1;  // `out` is one buffer that holds every earlier block
#if LZ4_VERSION_NUMBER >= 10904
  const bool own_checksum = content_checksum && !block_checksums;
  options.skipChecksums = own_checksum ? 1U : 0U;
#else
  const bool own_checksum = false;
#endif
  std::size_t in_pos = 0;
  std::size_t out_pos = 0;
  for (;;) {
    std::size_t src = in_size - in_pos;
    std::size_t dst = out.size() - out_pos;
    const std::size_t hint = LZ4F_decompress(ctx.get(), out.data() + out_pos, &dst, in + in_pos, &src, &options);
    if (LZ4F_isError(hint)) {
      throw FormatError(what + ": LZ4 data is corrupt (" + LZ4F_getErrorName(hint) + ")");
    }
    in_pos += src;
    out_pos += dst;
    if (hint == 0) break;  // frame complete
    if (src == 0 && dst == 0) {
      throw FormatError(what + ": LZ4 frame is truncated or longer than the " + std::to_string(uncompressed_size) +
                        " bytes the header states");
    }
  }
  if (out_pos != uncompressed_size) {
    throw FormatError(what + ": LZ4 chunk decompresses to " + std::to_string(out_pos) + " bytes, header says " +
                      std::to_string(uncompressed_size));
  }
  if (own_checksum) {
    // A complete frame ends with its 4-byte little-endian content checksum.
    std::uint32_t stated = 0;
    if (in_pos < 4) throw FormatError(what + ": LZ4 frame ends without its content checksum");
    std::memcpy(&stated, in + in_pos - 4, 4);
    const std::uint32_t got = xxh32(out.data(), out_pos);
    if (got != stated) {
      throw FormatError(what + ": LZ4 content checksum is " + std::to_string(got) + ", the frame says " +
                        std::to_string(stated));
    }
  }
}

/// Zstandard frame into exactly `uncompressed_size` bytes of `out`.
inline void decompress_zstd(const std::uint8_t* in, std::size_t in_size, std::uint64_t uncompressed_size,
                            std::vector<std::uint8_t>& out, const std::string& what) {
  check_chunk_size(uncompressed_size, what);
  check_expansion(in_size, uncompressed_size, kMaxZstdRatio, "zstd", what);
  out.resize(static_cast<std::size_t>(uncompressed_size));
  const std::size_t n = ZSTD_decompress(out.data(), out.size(), in, in_size);
  if (ZSTD_isError(n) != 0U) throw FormatError(what + ": zstd data is corrupt (" + ZSTD_getErrorName(n) + ")");
  if (n != uncompressed_size) {
    throw FormatError(what + ": zstd chunk decompresses to " + std::to_string(n) + " bytes, header says " +
                      std::to_string(uncompressed_size));
  }
}

}  // namespace semlio::io::detail
