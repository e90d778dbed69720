#include "models/dma_stream.hpp"

#include <algorithm>

namespace tbdr {

void DmaStream::add(std::uint64_t addr, std::uint64_t bytes) {
  for_each_request(addr, bytes, [&](std::uint64_t a, std::uint32_t n) { chunks_.push_back({a, n}); });
}

void DmaStream::reset(Client client, bool write, DramClass cls, std::uint32_t outstanding) {
  client_ = client;
  write_ = write;
  cls_ = cls;
  outstanding_ = outstanding;
  chunks_.clear();
  next_ = 0;
  completed_ = 0;
  in_flight_ = 0;
  waiting_ = false;
  done_ = nullptr;
}

void DmaStream::start(std::function<void()> done) {
  done_ = std::move(done);
  if (chunks_.empty()) {
    eq_.schedule(eq_.now(), [this] { finish(); });
    return;
  }
  pump();
}

void DmaStream::finish() {
  const std::function<void()> done = std::move(done_);
  done_ = nullptr;
  done();
  if (idle_ != nullptr) idle_->push_back(this);
}

void DmaStream::pump() {
  waiting_ = false;
  while (in_flight_ < outstanding_ && next_ < chunks_.size()) {
    const auto& ch = chunks_[next_];
    const bool ok = mem_.issue(client_, ch.first, ch.second, write_, cls_, [this] {
      --in_flight_;
      if (++completed_ == chunks_.size()) {
        finish();
        return;
      }
      if (!waiting_) pump();
    });
    if (!ok) {
      waiting_ = true;
      mem_.notify_when_ready([this] { pump(); });
      return;
    }
    ++in_flight_;
    ++next_;
  }
}

}  // namespace tbdr
