#pragma once
/// \file
/// The one k-best insertion shared by every k-nearest search in semlio
/// (KdTree3f, SmallKdTree3f, FeatureMap's cached lists): ties in squared
/// distance are broken by the smaller index, so every search returns the same
/// neighbours in the same order whatever structure found them -- what lets a
/// fast path be tested for equality against its reference.
#include <cstddef>
#include <cstdint>

namespace semlio::detail {

/// Inserts (d, i) into the list idx/d2, ascending by (distance, index), of
/// size `count` and capacity k >= 1; returns the new size. A candidate that
/// does not beat the k-th entry of a full list is dropped. No allocation.
inline std::size_t insert_by_distance_index(float d, std::uint32_t i, std::uint32_t* idx, float* d2, std::size_t count,
                                            std::size_t k) {
  const auto less = [](float a, std::uint32_t ia, float b, std::uint32_t ib) { return a < b || (a == b && ia < ib); };
  if (count == k && !less(d, i, d2[k - 1], idx[k - 1])) return count;
  std::size_t j = count < k ? count : k - 1;
  while (j > 0 && less(d, i, d2[j - 1], idx[j - 1])) {
    d2[j] = d2[j - 1];
    idx[j] = idx[j - 1];
    --j;
  }
  d2[j] = d;
  idx[j] = i;
  return count < k ? count + 1 : count;
}

}  // namespace semlio::detail
