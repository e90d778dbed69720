#pragma once
// A first-in first-out queue in one ring of slots that is reused as it empties and refills: a
// queue that keeps growing and shrinking around a few elements allocates nothing once its ring is
// as large as it has ever been (std::deque allocates and frees a block each time its end crosses
// one: the memory system's overflow queues did so 65,000 times in a 1080p deferred frame).
#include <cstddef>
#include <utility>
#include <vector>

namespace tbdr {

/// A FIFO of movable, default-constructible T in a ring whose size doubles when full. Popped
/// slots keep their (moved-from or old) contents until pushed over.
template <class T>
class RingQueue {
 public:
  bool empty() const { return size_ == 0; }
  std::size_t size() const { return size_; }
  /// The oldest element (precondition: not empty).
  T& front() { return ring_[head_]; }
  const T& front() const { return ring_[head_]; }
  void push_back(T&& v) {
    if (size_ == ring_.size()) grow();
    ring_[(head_ + size_) & (ring_.size() - 1)] = std::move(v);
    ++size_;
  }
  /// Drops the oldest element (precondition: not empty).
  void pop_front() {
    head_ = (head_ + 1) & (ring_.size() - 1);
    --size_;
  }

 private:
  /// Doubles the ring (at least 8 slots), the elements moved to its start in order.
  void grow() {
    std::vector<T> bigger(ring_.empty() ? 8 : 2 * ring_.size());
    for (std::size_t i = 0; i < size_; ++i) bigger[i] = std::move(ring_[(head_ + i) & (ring_.size() - 1)]);
    ring_ = std::move(bigger);
    head_ = 0;
  }
  std::vector<T> ring_;  ///< a power of two slots (or none)
  std::size_t head_ = 0;
  std::size_t size_ = 0;
};

}  // namespace tbdr
