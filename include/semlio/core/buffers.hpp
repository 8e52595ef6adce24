#pragma once
/// \file
/// Growth policy of the buffers that are refilled every frame or keyframe.
///
/// A buffer regrown to the exact size it needs reallocates again as soon as
/// a later input is one element larger, and inputs that hover around a size
/// (a local map while keyframes come and go, the features of a scan) keep
/// doing that long after warm-up. Growing by at least half and with an
/// eighth of headroom ends it after a few steps, and keeps a steadily
/// growing map from reallocating on every keyframe.

#include <algorithm>
#include <cstddef>
#include <memory>
#include <new>
#include <type_traits>
#include <utility>

namespace semlio {

/// Makes room for n elements in v (a std::vector or alike), keeping its
/// content: nothing when it has the capacity, else capacity max(n + n/8,
/// 1.5 x the old one) -- exactly n while v has never held anything, for
/// one-off uses.
template <typename Buffer>
void reserve_with_headroom(Buffer& v, std::size_t n) {
  if (v.capacity() >= n) return;
  const std::size_t old = v.capacity();
  v.reserve(old == 0 ? n : std::max(n + n / 8, old + old / 2));
}

/// As reserve_with_headroom for a buffer about to be overwritten whole: when
/// it must grow it is emptied first, so that its old content is not copied
/// into the new storage. v must not be the source of the data it receives.
template <typename Buffer>
void reserve_discarding(Buffer& v, std::size_t n) {
  if (v.capacity() >= n) return;
  v.clear();
  reserve_with_headroom(v, n);
}

/// std::allocator whose value-less construct() default-initialises: a
/// std::vector<T, DefaultInitAllocator<T>> of a trivial T leaves the elements
/// that resize() adds uninitialised instead of zeroing them. For caches
/// whose entries are only read once written (a state flag says so): a
/// zero-filled map-sized cache was a memset and the page faults of every
/// page of it at every growth, though most entries are never used.
template <typename T, typename Base = std::allocator<T>>
class DefaultInitAllocator : public Base {
  using Traits = std::allocator_traits<Base>;

 public:
  /// The same allocator for another element type.
  template <typename U>
  struct rebind {
    using other = DefaultInitAllocator<U, typename Traits::template rebind_alloc<U>>;  ///< the rebound type
  };

  using Base::Base;

  /// Default-initialises *p (no zeroing for trivial U).
  template <typename U>
  void construct(U* p) noexcept(std::is_nothrow_default_constructible_v<U>) {
    ::new (static_cast<void*>(p)) U;
  }
  /// Constructs *p from args, as Base does.
  template <typename U, typename... Args>
  void construct(U* p, Args&&... args) {
    Traits::construct(static_cast<Base&>(*this), p, std::forward<Args>(args)...);
  }
};

}  // namespace semlio
