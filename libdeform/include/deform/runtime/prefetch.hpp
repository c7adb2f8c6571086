#pragma once
// Cache hints for state a later call will touch (software prefetch): they change no result and no state. What they
// are for: a crowd, where each character's per-frame state (its springs, lattices, pose; a few dozen small arrays)
// is cold when its update() starts, and each array's first line would otherwise be a separate wait on memory. A
// hint issued for all of them at once overlaps those waits (docs/performance.md has the measured effect).
#include <cstddef>
#include <span>
#include <vector>

#include "deform/runtime/portable.hpp"

namespace deform {

// Hints that [data, data + bytes) will be read or written soon: a prefetch for writing where the target has one
// (PREFETCHW), else into every cache level; nothing where the compiler has no prefetch (portable.hpp).
inline void prefetch_bytes(const void* data, std::size_t bytes) noexcept {
  // Every 64-byte line of the range: one hint per 64 bytes from its start, and its last byte's line. (Addresses
  // stay pointers into the range: aligned through integer casts, GCC 12 compiled the hints to nothing.)
  const char* const p = static_cast<const char*>(data);
  for (std::size_t offset = 0; offset < bytes; offset += 64) DEFORM_PREFETCH(p + offset, 1);
  if (bytes > 0) DEFORM_PREFETCH(p + bytes - 1, 1);
}

template <class T>
void prefetch_span(std::span<const T> values) noexcept {
  prefetch_bytes(values.data(), values.size_bytes());
}

template <class T>
void prefetch_span(const std::vector<T>& values) noexcept {
  prefetch_bytes(values.data(), values.size() * sizeof(T));
}

}  // namespace deform
