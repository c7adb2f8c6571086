#pragma once
// Cache hints for state a later call will touch (software prefetch): they change no result and no state. What they
// are for: a crowd, where each character's per-frame state (its springs, lattices, pose; a few dozen small arrays)
// is cold when its update() starts, and each array's first line would otherwise be a separate wait on memory. A
// hint issued for all of them at once overlaps those waits (docs/performance.md has the measured effect).
#include <cstddef>
#include <cstdint>
#include <span>
#include <vector>

namespace deform {

// Hints that [data, data + bytes) will be written soon (read and written: the line is fetched for ownership).
// Nothing on compilers without __builtin_prefetch.
inline void prefetch_bytes(const void* data, std::size_t bytes) noexcept {
#if defined(__GNUC__) || defined(__clang__)
  if (bytes == 0) return;
  // Each 64-byte line the range touches, once.
  const auto first = reinterpret_cast<std::uintptr_t>(data) & ~std::uintptr_t(63);
  const auto last = (reinterpret_cast<std::uintptr_t>(data) + bytes - 1) & ~std::uintptr_t(63);
  for (std::uintptr_t line = first; line <= last; line += 64)
    __builtin_prefetch(reinterpret_cast<const void*>(line), 1, 3);
#else
  (void)data;
  (void)bytes;
#endif
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
