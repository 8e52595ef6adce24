#pragma once
/// \file
/// Stable LSD radix sort by an unsigned integer key, for the large sorts that
/// run every frame or keyframe (LocalMap's merged voxel entries, VoxelGrid's
/// output order), where a comparison sort through the elements cost several
/// times more. 11-bit digits; a digit equal in every key costs one histogram
/// and no pass. Allocation-free once the caller's scratch buffer and
/// histograms have grown.

#include <algorithm>
#include <cstddef>
#include <cstdint>
#include <utility>
#include <vector>

namespace semlio {

/// Digit histograms of radix_sort_by_key (2048 buckets a digit; 96 KiB,
/// room for 64-bit keys), kept by callers that sort repeatedly so that a sort
/// allocates nothing.
struct RadixCounts {
  static constexpr int kDigit = 11;                                  ///< bits per digit
  static constexpr std::size_t kBuckets = std::size_t{1} << kDigit;  ///< buckets per digit
  std::vector<std::size_t> count;                                    ///< passes * kBuckets, sized on use
};

/// Sorts items by key_of(item) -- a std::uint64_t below 2^key_bits (1..64) --
/// keeping the input order among equal keys. The result is in `items`;
/// `scratch` and `counts` are work space.
template <typename T, typename KeyOf>
void radix_sort_by_key(std::vector<T>& items, std::vector<T>& scratch, RadixCounts& counts, int key_bits,
                       KeyOf key_of) {
  constexpr int kDigit = RadixCounts::kDigit;
  constexpr std::size_t kBuckets = RadixCounts::kBuckets;
  const std::size_t n = items.size();
  if (n < 2) return;
  const int passes = (std::clamp(key_bits, 1, 64) + kDigit - 1) / kDigit;
  // Room for the widest keys at once: a later call with wider keys (a scan
  // with more points) then allocates nothing either.
  constexpr std::size_t kMostPasses = (64 + kDigit - 1) / kDigit;
  counts.count.reserve(kMostPasses * kBuckets);
  counts.count.assign(static_cast<std::size_t>(passes) * kBuckets, 0);
  const auto histogram = [&counts](int d) { return counts.count.data() + static_cast<std::size_t>(d) * kBuckets; };
  for (const T& item : items) {
    const std::uint64_t key = key_of(item);
    for (int d = 0; d < passes; ++d) ++histogram(d)[(key >> (d * kDigit)) & (kBuckets - 1)];
  }
  scratch.resize(n);
  for (int d = 0; d < passes; ++d) {
    std::size_t* offset = histogram(d);
    if (std::find(offset, offset + kBuckets, n) != offset + kBuckets) continue;  // one bucket holds all
    std::size_t sum = 0;
    for (std::size_t b = 0; b < kBuckets; ++b) sum += std::exchange(offset[b], sum);
    const int shift = d * kDigit;
    for (const T& item : items) scratch[offset[(key_of(item) >> shift) & (kBuckets - 1)]++] = item;
    items.swap(scratch);
  }
}

}  // namespace semlio
