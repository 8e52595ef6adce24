#pragma once
/// \file
/// One-shot decompression of a bag chunk whose uncompressed size the
/// container states (ROS 1 bag chunk header `size`, MCAP Chunk
/// `uncompressed_size`): bz2, LZ4 frame format and Zstandard. Part of the
/// optional semlio::io_bags component: needs libbz2, liblz4 and libzstd.
/// Every failure, including output that is longer or shorter than stated,
/// throws FormatError naming `what` (the file and the chunk's offset).

#include <bzlib.h>
#include <lz4frame.h>
#include <zstd.h>

#include <cstddef>
#include <cstdint>
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

/// bz2 stream `in` into exactly `uncompressed_size` bytes of `out`.
inline void decompress_bz2(const std::uint8_t* in, std::size_t in_size, std::uint64_t uncompressed_size,
                           std::vector<std::uint8_t>& out, const std::string& what) {
  check_chunk_size(uncompressed_size, what);
  if (in_size > std::numeric_limits<unsigned int>::max()) throw FormatError(what + ": bz2 chunk too large");
  out.resize(static_cast<std::size_t>(uncompressed_size));
  auto dest_len = static_cast<unsigned int>(uncompressed_size);
  // bzlib takes non-const pointers but does not write through `source`.
  const int rc = BZ2_bzBuffToBuffDecompress(reinterpret_cast<char*>(out.data()), &dest_len,
                                            const_cast<char*>(reinterpret_cast<const char*>(in)),
                                            static_cast<unsigned int>(in_size), 0, 0);
  if (rc != BZ_OK) throw FormatError(what + ": bz2 data is corrupt (bzlib error " + std::to_string(rc) + ")");
  if (dest_len != uncompressed_size) {
    throw FormatError(what + ": bz2 chunk decompresses to " + std::to_string(dest_len) + " bytes, header says " +
                      std::to_string(uncompressed_size));
  }
}

/// LZ4 frame (LZ4F, what roslz4 and MCAP write) into exactly
/// `uncompressed_size` bytes of `out`.
inline void decompress_lz4_frame(const std::uint8_t* in, std::size_t in_size, std::uint64_t uncompressed_size,
                                 std::vector<std::uint8_t>& out, const std::string& what) {
  check_chunk_size(uncompressed_size, what);
  out.resize(static_cast<std::size_t>(uncompressed_size));
  LZ4F_dctx* raw = nullptr;
  if (LZ4F_isError(LZ4F_createDecompressionContext(&raw, LZ4F_VERSION))) {
    throw FormatError(what + ": cannot create an LZ4 decompression context");
  }
  const std::unique_ptr<LZ4F_dctx, decltype(&LZ4F_freeDecompressionContext)> ctx(raw, &LZ4F_freeDecompressionContext);
  std::size_t in_pos = 0;
  std::size_t out_pos = 0;
  for (;;) {
    std::size_t src = in_size - in_pos;
    std::size_t dst = out.size() - out_pos;
    const std::size_t hint = LZ4F_decompress(ctx.get(), out.data() + out_pos, &dst, in + in_pos, &src, nullptr);
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
}

/// Zstandard frame into exactly `uncompressed_size` bytes of `out`.
inline void decompress_zstd(const std::uint8_t* in, std::size_t in_size, std::uint64_t uncompressed_size,
                            std::vector<std::uint8_t>& out, const std::string& what) {
  check_chunk_size(uncompressed_size, what);
  out.resize(static_cast<std::size_t>(uncompressed_size));
  const std::size_t n = ZSTD_decompress(out.data(), out.size(), in, in_size);
  if (ZSTD_isError(n) != 0U) throw FormatError(what + ": zstd data is corrupt (" + ZSTD_getErrorName(n) + ")");
  if (n != uncompressed_size) {
    throw FormatError(what + ": zstd chunk decompresses to " + std::to_string(n) + " bytes, header says " +
                      std::to_string(uncompressed_size));
  }
}

}  // namespace semlio::io::detail
