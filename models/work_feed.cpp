#include "models/work_feed.hpp"

#include <chrono>
#include <stdexcept>
#include <string>
#include <utility>

namespace tbdr {

WorkFeed::Published WorkFeed::complete(const CommandWork& cmd) {
  Published p;
  p.complete = true;
  for (const RenderWork& r : cmd.renders) {
    p.renders.push_back(&r);
    p.tiles.push_back(r.tiles.size());
    p.published.push_back(r.tiles.size());
  }
  return p;
}

WorkFeed::WorkFeed(const FrameWork& work)
    : work_(&work), begun_(true), closed_(true), expected_(work.commands.size()) {
  for (const CommandWork& c : work.commands) state_.push_back(complete(c));
}

void WorkFeed::begin(const FrameWork& frame, std::size_t commands) {
  std::lock_guard lock(mutex_);
  if (begun_ || closed_) throw std::logic_error("WorkFeed::begin: the feed has begun already");
  own_ = frame;
  own_.commands.clear();
  // Reserved once: opening a command never moves one the consumer may be reading.
  own_.commands.reserve(commands);
  state_.reserve(commands);
  expected_ = commands;
  begun_ = true;
  changed_.notify_all();
}

CommandWork& WorkFeed::open(CommandWork&& header) {
  std::lock_guard lock(mutex_);
  if (!begun_ || closed_ || work_ != &own_) throw std::logic_error("WorkFeed::open: the feed is not open");
  if (own_.commands.size() == expected_) throw std::logic_error("WorkFeed::open: more commands than begin() announced");
  // Earlier commands may still be open only with no renders to come: a pass whose renders are all
  // binned (its latest is not partial: its tiles are what is left of it), or a dispatch (opened
  // before it runs: its content is what is left of it). The last pass binned ahead and the
  // dispatches after it are what may be open beside the new command.
  bool open_pass = false;
  for (std::size_t c = 0; c < state_.size(); ++c) {
    const Published& p = state_[c];
    if (p.complete) continue;
    if (own_.commands[c].is_dispatch) continue;
    if (open_pass || p.renders.empty() || p.renders.back()->partial) {
      throw std::logic_error("WorkFeed::open: an earlier command is open with renders to come");
    }
    open_pass = true;
  }
  if (!header.renders.empty()) throw std::logic_error("WorkFeed::open: a command is opened before its renders");
  own_.commands.push_back(std::move(header));
  state_.emplace_back();
  changed_.notify_all();
  return own_.commands.back();
}

std::size_t WorkFeed::last_opened() const {
  std::lock_guard lock(mutex_);
  if (state_.empty()) throw std::logic_error("WorkFeed::last_opened: no command yet");
  return state_.size() - 1;
}

WorkFeed::Published& WorkFeed::open_state(std::size_t c, const char* what) {
  if (c >= state_.size() || state_[c].complete) throw std::logic_error(std::string("WorkFeed::") + what + ": the command is not open");
  return state_[c];
}

void WorkFeed::publish_render(std::size_t c, std::size_t tiles) {
  std::lock_guard lock(mutex_);
  Published& p = open_state(c, "publish_render");
  if (!p.renders.empty() && !p.renders.back()->partial) {
    throw std::logic_error("WorkFeed::publish_render: a render after the command's last (not partial) one");
  }
  const RenderWork& r = own_.commands[c].renders.back();
  if (r.tiles.capacity() < tiles || !r.tiles.empty()) throw std::logic_error("WorkFeed::publish_render: no room reserved for its tiles");
  p.renders.push_back(&r);
  p.tiles.push_back(tiles);
  p.published.push_back(0);
  changed_.notify_all();
}

void WorkFeed::publish_tiles(std::size_t c, std::size_t ready) {
  {
    std::lock_guard lock(mutex_);
    Published& p = open_state(c, "publish_tiles");
    if (p.renders.empty()) throw std::logic_error("WorkFeed::publish_tiles: no render is open");
    if (ready > p.tiles.back()) throw std::logic_error("WorkFeed::publish_tiles: more tiles than the render announced");
    if (ready <= p.published.back()) return;
    p.published.back() = ready;
  }
  changed_.notify_all();
}

void WorkFeed::close_command(std::size_t c) {
  std::lock_guard lock(mutex_);
  Published& p = open_state(c, "close_command");
  if (c > 0 && !state_[c - 1].complete) throw std::logic_error("WorkFeed::close_command: the previous command is open");
  for (std::size_t r = 0; r < p.renders.size(); ++r) {
    if (p.published[r] != p.tiles[r]) throw std::logic_error("WorkFeed::close_command: a render has tiles not published");
  }
  if (p.renders.size() != own_.commands[c].renders.size()) throw std::logic_error("WorkFeed::close_command: a render was not published");
  p.complete = true;
  changed_.notify_all();
}

void WorkFeed::publish(CommandWork&& cmd) {
  std::lock_guard lock(mutex_);
  if (!begun_ || closed_ || work_ != &own_) throw std::logic_error("WorkFeed::publish: the feed is not open");
  if (own_.commands.size() == expected_) throw std::logic_error("WorkFeed::publish: more commands than begin() announced");
  if (!state_.empty() && !state_.back().complete) throw std::logic_error("WorkFeed::publish: the previous command is open");
  own_.commands.push_back(std::move(cmd));
  state_.push_back(complete(own_.commands.back()));
  changed_.notify_all();
}

void WorkFeed::close() {
  std::lock_guard lock(mutex_);
  closed_ = true;
  changed_.notify_all();
}

template <class Ready>
void WorkFeed::wait_until(std::unique_lock<std::mutex>& lock, Ready ready) {
  if (ready() || closed_) return;
  const auto from = std::chrono::steady_clock::now();
  ++waits_;
  changed_.wait(lock, [&] { return ready() || closed_; });
  wait_seconds_ += std::chrono::duration<double>(std::chrono::steady_clock::now() - from).count();
}

void WorkFeed::wait_begun(std::unique_lock<std::mutex>& lock) {
  wait_until(lock, [this] { return begun_; });
}

double WorkFeed::consumer_wait_seconds() const {
  std::lock_guard lock(mutex_);
  return wait_seconds_;
}

std::uint64_t WorkFeed::consumer_waits() const {
  std::lock_guard lock(mutex_);
  return waits_;
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
  wait_until(lock, [&] { return c < state_.size(); });
  return c < state_.size() ? &work_->commands[c] : nullptr;
}

void WorkFeed::wait_complete(std::size_t c) {
  std::unique_lock lock(mutex_);
  wait_until(lock, [&] { return c < state_.size() && state_[c].complete; });
}

const RenderWork* WorkFeed::wait_render(std::size_t c, std::size_t r) {
  std::unique_lock lock(mutex_);
  // No render follows a complete command's last, nor an open command's render that is not partial.
  const auto known = [&] {
    if (c >= state_.size()) return false;
    const Published& p = state_[c];
    return r < p.renders.size() || p.complete || (!p.renders.empty() && !p.renders.back()->partial);
  };
  wait_until(lock, known);
  return c < state_.size() && r < state_[c].renders.size() ? state_[c].renders[r] : nullptr;
}

std::size_t WorkFeed::tile_count(std::size_t c, std::size_t r) {
  std::lock_guard lock(mutex_);
  return state_.at(c).tiles.at(r);
}

const TileWork* WorkFeed::wait_tile(std::size_t c, std::size_t r, std::size_t i) {
  std::unique_lock lock(mutex_);
  const auto ready = [&] { return c < state_.size() && r < state_[c].renders.size() && i < state_[c].published[r]; };
  wait_until(lock, ready);
  // The tiles' storage was reserved before the render was published: it does not move.
  return ready() ? state_[c].renders[r]->tiles.data() + i : nullptr;
}

FrameWork WorkFeed::take() {
  std::lock_guard lock(mutex_);
  if (!closed_) throw std::logic_error("WorkFeed::take: the feed is still open");
  if (work_ != &own_) return *work_;
  state_.clear();
  return std::move(own_);
}

}  // namespace tbdr
