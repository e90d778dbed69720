#pragma once
// A pool of slots with stable indices: in-flight requests, fills and callbacks are kept by index
// and their slots reused once released, so a long run allocates only as many as are ever live.
#include <cstdint>
#include <vector>

namespace tbdr {

/// Slots addressed by index, with a free list: acquire() reuses the most recently released slot
/// (its old contents are left for the caller to overwrite) or appends a default-constructed one.
template <class T>
class SlotPool {
 public:
  std::uint32_t acquire() {
    if (free_.empty()) {
      slots_.emplace_back();
      return static_cast<std::uint32_t>(slots_.size() - 1);
    }
    const std::uint32_t i = free_.back();
    free_.pop_back();
    return i;
  }
  void release(std::uint32_t i) { free_.push_back(i); }
  T& operator[](std::uint32_t i) { return slots_[i]; }
  const T& operator[](std::uint32_t i) const { return slots_[i]; }
  /// Slots ever created (live + free).
  std::size_t capacity() const { return slots_.size(); }
  /// Slots acquired and not released.
  std::size_t live() const { return slots_.size() - free_.size(); }

 private:
  std::vector<T> slots_;
  std::vector<std::uint32_t> free_;
};

}  // namespace tbdr
