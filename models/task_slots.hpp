#pragma once
// The task slots of the unified shading clusters: how many shader tasks (usc.threads_per_task
// threads each) can be resident at once across the USCs (usc.tasks_in_flight). Resident tasks are
// what hides memory latency: while one waits for a texture or attachment read, the others issue
// ALU work and their own reads. Work that needs slots waits, in arrival order, until they are free.
#include <cstdint>
#include <deque>
#include <functional>
#include <stdexcept>
#include <utility>

namespace tbdr {

/// A counting pool of resident-task slots with first-come, first-served admission.
class TaskSlots {
 public:
  explicit TaskSlots(std::uint64_t total) : total_(total), free_(total) {
    if (total == 0) throw std::invalid_argument("task slots: at least one slot needed");
  }

  std::uint64_t total() const { return total_; }
  std::uint64_t free() const { return free_; }
  /// Slots work of `tasks` tasks holds while resident: all of them, or every slot if there are fewer.
  std::uint64_t slots_for(std::uint64_t tasks) const { return tasks < total_ ? tasks : total_; }

  /// Takes `n` slots (n <= total) as soon as they are free and no earlier request waits; runs
  /// `admitted` then (immediately when possible, else from release()).
  void acquire(std::uint64_t n, std::function<void()> admitted) {
    if (n > total_) throw std::invalid_argument("task slots: request larger than the pool");
    if (waiting_.empty() && n <= free_) {
      free_ -= n;
      admitted();
      return;
    }
    waiting_.push_back({n, std::move(admitted)});
  }
  /// Returns `n` slots and admits the waiting requests that now fit, in order.
  void release(std::uint64_t n) {
    free_ += n;
    while (!waiting_.empty() && waiting_.front().first <= free_) {
      auto next = std::move(waiting_.front());
      waiting_.pop_front();
      free_ -= next.first;
      next.second();
    }
  }
  /// Requests waiting for slots.
  std::size_t waiting() const { return waiting_.size(); }

 private:
  std::uint64_t total_;
  std::uint64_t free_;
  std::deque<std::pair<std::uint64_t, std::function<void()>>> waiting_;
};

}  // namespace tbdr
