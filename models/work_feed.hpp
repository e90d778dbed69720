#pragma once
// How a frame's work reaches the timing model: command by command, as the functional run
// completes each, so that the timing model can run on its own thread beside the functional run
// (run_driver with more than one thread). The timing model waits for a command only when its
// schedule needs it and reads it once complete, so its results are the same whether the work
// was all there before it started or arrived while it ran.
#include <condition_variable>
#include <cstddef>
#include <mutex>

#include "models/frame_work.hpp"

namespace tbdr {

/// A frame's work handed from its producer (the functional run) to its consumer (the timing model).
class WorkFeed {
 public:
  /// An open feed: the producer calls begin(), publish() per command, then close().
  WorkFeed() = default;
  /// A closed feed of a frame whose work is complete (`work` must outlive the feed).
  explicit WorkFeed(const FrameWork& work);
  WorkFeed(const WorkFeed&) = delete;
  WorkFeed& operator=(const WorkFeed&) = delete;

  // ---- producer ----
  /// The frame's fields (its commands are ignored) and the number of commands that will follow.
  void begin(const FrameWork& frame, std::size_t commands);
  /// Appends the next command, complete. Throws std::logic_error past the number begin() gave.
  void publish(CommandWork&& cmd);
  /// No more commands: after the last, or when the producer failed (the consumer stops waiting).
  void close();

  // ---- consumer ----
  /// The frame's fields, once begin() was called (or the feed was closed without it: then an
  /// empty frame). Its commands are read through wait_for only.
  const FrameWork& frame();
  /// How many commands the frame has (as begin() announced).
  std::size_t expected_commands();
  /// Command `c` once it is published (the reference stays valid for the feed's life), or nullptr
  /// when the feed was closed without it.
  const CommandWork* wait_for(std::size_t c);

  /// The whole frame's work (moved out of an open feed; a copy of a complete frame's), once the
  /// feed is closed and the consumer done with it.
  FrameWork take();

 private:
  void wait_begun(std::unique_lock<std::mutex>& lock);
  std::mutex mutex_;
  std::condition_variable changed_;
  FrameWork own_;                      ///< an open feed's frame (its commands vector never reallocates)
  const FrameWork* work_ = &own_;      ///< the frame read: own_ or a complete frame's
  bool begun_ = false, closed_ = false;
  std::size_t published_ = 0, expected_ = 0;
};

}  // namespace tbdr
