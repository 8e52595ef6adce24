#pragma once
/// \file
/// Growth policy of the buffers that are refilled every frame or keyframe.
///
/// A buffer regrown to the exact size it needs reallocates again as soon as
/// a later input is one element larger, and inputs that hover around a size
/// (a local map while keyframes come and go, the features of a scan) keep
/// doing that long after warm-up. Growing with an eighth of headroom ends it
/// after a few steps at a memory cost of at most 12.5 %.

#include <cstddef>

namespace semlio {

/// Makes room for n elements in v (a std::vector or alike) without touching
/// its content: nothing when it has the capacity, else capacity n plus an
/// eighth (exactly n while v has never held anything, for one-off uses).
template <typename Buffer>
void reserve_with_headroom(Buffer& v, std::size_t n) {
  if (v.capacity() >= n) return;
  v.reserve(v.capacity() == 0 ? n : n + n / 8);
}

}  // namespace semlio
