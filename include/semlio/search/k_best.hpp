#pragma once
/// \file
/// The one k-best insertion shared by every k-nearest search in semlio
/// (KdTree3f, SmallKdTree3f, FeatureMap's cached lists): ties in squared
/// distance are broken by the smaller index, so every search returns the same
/// neighbours in the same order whatever structure found them -- what lets a
/// fast path be tested for equality against its reference. KBest keeps the
/// same order for the hot searches (k <= 64) in less work.
#include <array>
#include <bit>
#include <cstddef>
#include <cstdint>
#include <utility>

namespace semlio::detail {

/// (squared distance, index) as one integer in the same order. A squared
/// distance is a sum of squares, so +0 or positive (never -0), and the bit
/// patterns of non-negative floats order as unsigned integers; a NaN (only
/// from a NaN query) sorts after every number. One integer comparison
/// replaces a float comparison and an index tie-break -- the hottest branches
/// of every k-nearest search (10-NN axes 7 %, 32-NN lists 5 % faster,
/// benchmark `MapKnn/*` in bench_gauss_newton; full-preset frame median 37.0 -> 34.2 ms: bench_frame_time).
inline std::uint64_t distance_index_key(float sq_dist, std::uint32_t index) noexcept {
  return (std::uint64_t{std::bit_cast<std::uint32_t>(sq_dist)} << 32U) | index;
}

/// Inserts (d, i) into the list idx/d2, ascending by (distance, index), of
/// size `count` and capacity k >= 1; returns the new size. A candidate that
/// does not beat the k-th entry of a full list is dropped. d is a squared
/// distance (see distance_index_key). No allocation.
inline std::size_t insert_by_distance_index(float d, std::uint32_t i, std::uint32_t* idx, float* d2, std::size_t count,
                                            std::size_t k) {
  const std::uint64_t key = distance_index_key(d, i);
  if (count == k && key >= distance_index_key(d2[k - 1], idx[k - 1])) return count;
  std::size_t j = count < k ? count : k - 1;
  while (j > 0 && key < distance_index_key(d2[j - 1], idx[j - 1])) {
    d2[j] = d2[j - 1];
    idx[j] = idx[j - 1];
    --j;
  }
  d2[j] = d;
  idx[j] = i;
  return count < k ? count + 1 : count;
}

/// One compare-exchange of a sorting network: afterwards a[lo] <= a[hi].
struct CompareExchange {
  std::uint8_t lo;  ///< index that receives the smaller key
  std::uint8_t hi;  ///< index that receives the larger key
};

/// Calls f(lo, hi) for each compare-exchange of Batcher's odd-even merge
/// sort on N inputs (N a power of two), in the order they run.
template <std::size_t N, typename F>
constexpr void for_each_batcher_exchange(F&& f) {
  static_assert(N >= 2 && (N & (N - 1)) == 0, "Batcher's network sorts a power of two of inputs");
  for (std::size_t p = 1; p < N; p <<= 1U) {
    for (std::size_t k = p; k >= 1; k >>= 1U) {
      for (std::size_t j = k % p; j + k < N; j += 2 * k) {
        for (std::size_t i = 0; i < k && i < N - j - k; ++i) {
          if ((i + j) / (2 * p) == (i + j + k) / (2 * p)) f(i + j, i + j + k);
        }
      }
    }
  }
}

/// Number of compare-exchanges of that network: 5, 19 and 63 for 4, 8 and 16 inputs.
template <std::size_t N>
constexpr std::size_t batcher_network_size() {
  std::size_t c = 0;
  for_each_batcher_exchange<N>([&c](std::size_t, std::size_t) { ++c; });
  return c;
}

/// Batcher's odd-even merge sort on N inputs, as its list of compare-exchanges.
template <std::size_t N>
constexpr std::array<CompareExchange, batcher_network_size<N>()> batcher_network() {
  std::array<CompareExchange, batcher_network_size<N>()> out{};
  std::size_t c = 0;
  for_each_batcher_exchange<N>([&](std::size_t lo, std::size_t hi) {
    out[c++] = CompareExchange{static_cast<std::uint8_t>(lo), static_cast<std::uint8_t>(hi)};
  });
  return out;
}

/// The network sort_keys<N> runs.
template <std::size_t N>
inline constexpr auto kBatcherNetwork = batcher_network<N>();

// sort_keys' body: one compare-exchange per network entry, unrolled.
template <std::size_t N, std::size_t... I>
inline void sort_keys_unrolled(std::uint64_t* a, std::index_sequence<I...>) noexcept {
  const auto exchange = [a](std::size_t lo, std::size_t hi) {
    const std::uint64_t x = a[lo];
    const std::uint64_t y = a[hi];
    a[lo] = x < y ? x : y;
    a[hi] = x < y ? y : x;
  };
  (exchange(kBatcherNetwork<N>[I].lo, kBatcherNetwork<N>[I].hi), ...);
}

/// Sorts a[0..N) ascending (N = 4, 8, 16, ...) by a sorting network: a fixed
/// sequence of min / max pairs (conditional moves), so no branch depends on
/// the keys. Why: SmallKdTree3f hands the candidates of a search's first
/// leaf -- up to 16 at once, in no useful order -- to an empty KBest; offered
/// one by one, each costs its shifts and a data-dependent exit of the
/// insertion loop (file comment of small_kdtree.hpp for the numbers).
template <std::size_t N>
inline void sort_keys(std::uint64_t* a) noexcept {
  sort_keys_unrolled<N>(a, std::make_index_sequence<kBatcherNetwork<N>.size()>{});
}

/// Most entries a KBest holds.
inline constexpr std::size_t kKBestMax = 64;

/// The k best (squared distance, index) pairs offered so far (k <= kKBestMax),
/// ascending by distance_index_key: the order insert_by_distance_index keeps,
/// so the same entries come out. Why a second form: it stores the keys
/// themselves behind a zero sentinel, so an insertion step is one load, one
/// integer comparison and one store, where insert_by_distance_index rebuilds
/// each key from two arrays and tests the list's start -- that loop was
/// ~10 % of a full-preset frame's instructions (callgrind, KITTI raw
/// snippet). Uninitialised beyond the sentinel: no per-query zeroing.
class KBest {
 public:
  /// Empty, for the k (1..kKBestMax) best.
  explicit KBest(std::size_t k) noexcept : k_(k) { keys_[0] = 0; }

  /// True when k entries are held.
  [[nodiscard]] bool full() const noexcept { return count_ == k_; }
  /// Entries held.
  [[nodiscard]] std::size_t size() const noexcept { return count_; }
  /// Squared distance of the last (worst) entry. Precondition: size() > 0.
  [[nodiscard]] float worst() const noexcept {
    return std::bit_cast<float>(static_cast<std::uint32_t>(keys_[count_] >> 32U));
  }

  /// Admits (d, i) when the list is not full or it beats the last entry.
  void offer(float d, std::uint32_t i) noexcept {
    const std::uint64_t key = distance_index_key(d, i);
    std::size_t j = 0;
    if (count_ == k_) {
      if (key >= keys_[k_]) return;
      j = k_;
    } else {
      j = ++count_;
    }
    // keys_[0] == 0 stops the walk: no key is below it.
    while (key < keys_[j - 1]) {
      keys_[j] = keys_[j - 1];
      --j;
    }
    keys_[j] = key;
  }

  /// Fills an empty KBest (precondition: size() == 0) with the first
  /// min(n, k) of `keys` (distance_index_key values, ascending and distinct):
  /// the same entries as offering all n keys one by one.
  void assign_sorted(const std::uint64_t* keys, std::size_t n) noexcept {
    n = n < k_ ? n : k_;
    for (std::size_t j = 0; j < n; ++j) keys_[j + 1] = keys[j];
    count_ = n;
  }

  /// Fills an empty KBest (precondition: size() == 0) from m <= 16 distinct
  /// keys in any order, overwriting keys[m..16) (keys is 16 long): they are
  /// padded with the largest key, sorted by the smallest network that holds
  /// them (sort_keys) and taken as one block -- the same entries as offering
  /// the m keys one by one, without an insertion per key (SmallKdTree3f's
  /// first leaf, see its file comment).
  void assign_unsorted(std::uint64_t* keys, std::size_t m) noexcept {
    for (std::size_t j = m; j < 16; ++j) keys[j] = ~std::uint64_t{0};
    if (m <= 4) {
      sort_keys<4>(keys);
    } else if (m <= 8) {
      sort_keys<8>(keys);
    } else {
      sort_keys<16>(keys);
    }
    assign_sorted(keys, m);
  }

  /// Writes the entries, ascending, into idx / d2 (each size() long); returns size().
  std::size_t write(std::uint32_t* idx, float* d2) const noexcept {
    for (std::size_t j = 0; j < count_; ++j) {
      const std::uint64_t key = keys_[j + 1];
      idx[j] = static_cast<std::uint32_t>(key);
      d2[j] = std::bit_cast<float>(static_cast<std::uint32_t>(key >> 32U));
    }
    return count_;
  }

 private:
  std::array<std::uint64_t, kKBestMax + 1> keys_;  // [0] = 0 (sentinel); entries at 1..count_
  std::size_t k_;
  std::size_t count_ = 0;
};

}  // namespace semlio::detail
