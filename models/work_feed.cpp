#include "models/work_feed.hpp"

#include <stdexcept>
#include <utility>

namespace tbdr {

WorkFeed::WorkFeed(const FrameWork& work)
    : work_(&work), begun_(true), closed_(true), published_(work.commands.size()), expected_(work.commands.size()) {}

void WorkFeed::begin(const FrameWork& frame, std::size_t commands) {
  std::lock_guard lock(mutex_);
  if (begun_ || closed_) throw std::logic_error("WorkFeed::begin: the feed has begun already");
  own_ = frame;
  own_.commands.clear();
  // Reserved once: publishing never moves a command the consumer may be reading.
  own_.commands.reserve(commands);
  expected_ = commands;
  begun_ = true;
  changed_.notify_all();
}

void WorkFeed::publish(CommandWork&& cmd) {
  std::lock_guard lock(mutex_);
  if (!begun_ || closed_ || work_ != &own_) throw std::logic_error("WorkFeed::publish: the feed is not open");
  if (own_.commands.size() == expected_) throw std::logic_error("WorkFeed::publish: more commands than begin() announced");
  own_.commands.push_back(std::move(cmd));
  ++published_;
  changed_.notify_all();
}

void WorkFeed::close() {
  std::lock_guard lock(mutex_);
  closed_ = true;
  changed_.notify_all();
}

void WorkFeed::wait_begun(std::unique_lock<std::mutex>& lock) {
  changed_.wait(lock, [this] { return begun_ || closed_; });
}

const FrameWork& WorkFeed::frame() {
  std::unique_lock lock(mutex_);
  wait_begun(lock);
  return *work_;
}

std::size_t WorkFeed::expected_commands() {
  std::unique_lock lock(mutex_);
  wait_begun(lock);
  return expected_;
}

const CommandWork* WorkFeed::wait_for(std::size_t c) {
  std::unique_lock lock(mutex_);
  changed_.wait(lock, [&] { return c < published_ || closed_; });
  return c < published_ ? &work_->commands[c] : nullptr;
}

FrameWork WorkFeed::take() {
  std::lock_guard lock(mutex_);
  if (!closed_) throw std::logic_error("WorkFeed::take: the feed is still open");
  if (work_ != &own_) return *work_;
  published_ = 0;
  return std::move(own_);
}

}  // namespace tbdr
