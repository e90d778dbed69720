#pragma once
// How a frame's work reaches the timing model: as the functional run produces it, so that the
// timing model can run on its own thread beside the functional run (run_driver with more than
// one thread). A command is opened when it starts (what the timing model needs to place it: its
// name, slots and buffers), then each of its renders when it is binned (its tile count known),
// then each of that render's tiles in dispatch order as the functional run has merged it, then
// the command is closed (complete); a command whose layout is known only at its end (a spilling
// pass, gpu.mode=imr's batches) is published complete at once, and so is a dispatch unless a pass
// is binned past it (below: it is opened with its header before it runs and closed once it has).
// The next command may be opened (and its renders binned) while the previous one's last render
// still renders: the functional run bins a pass before the tiles of the one before it (the
// hardware's two parameter buffers: geometry of the next render overlaps the fragment work of this
// one), also past the dispatches between them, which run after those tiles. The timing model waits
// for a piece only when its schedule needs it and reads it once published, so its results are the
// same whether the work was all there before it started or arrived while it ran.
#include <condition_variable>
#include <cstddef>
#include <mutex>
#include <vector>

#include "models/frame_work.hpp"

namespace tbdr {

/// A frame's work handed from its producer (the functional run) to its consumer (the timing model).
class WorkFeed {
 public:
  /// An open feed: the producer calls begin(), then per command open() ... close_command() or
  /// publish(), then close().
  WorkFeed() = default;
  /// A closed feed of a frame whose work is complete (`work` must outlive the feed).
  explicit WorkFeed(const FrameWork& work);
  WorkFeed(const WorkFeed&) = delete;
  WorkFeed& operator=(const WorkFeed&) = delete;

  // ---- producer ----
  /// The frame's fields (its commands are ignored) and the number of commands that will follow.
  void begin(const FrameWork& frame, std::size_t commands);
  /// Starts the next command from `header` (its fields but its renders final; no renders yet;
  /// a dispatch's content, filled before close_command, excepted) and returns where the producer
  /// appends its renders (its index: last_opened()). Throws std::logic_error past the number
  /// begin() gave, or while an earlier pass is open with renders to come (its latest render
  /// partial or none yet) or two earlier passes are open (open dispatches may be any number).
  CommandWork& open(CommandWork&& header);
  /// Index of the command open() opened last.
  std::size_t last_opened() const;
  /// Open command `c`'s latest render is binned: its binning and `partial` final (false: the
  /// command's last render), room reserved for its `tiles` tiles (appended later, each followed
  /// by publish_tiles; none may move).
  void publish_render(std::size_t c, std::size_t tiles);
  /// Open command `c`'s latest render has its first `ready` tiles appended and final. Threads
  /// that append tiles in turn may report them out of turn: a count below the one published
  /// changes nothing. The consumer is woken after the feed's lock is released (a woken consumer
  /// that preempts the producer finds the lock free).
  void publish_tiles(std::size_t c, std::size_t ready);
  /// Open command `c` is complete (all its renders and tiles final).
  void close_command(std::size_t c);
  /// Appends the next command, complete (open, every render and tile, close); every earlier one
  /// must be complete.
  void publish(CommandWork&& cmd);
  /// No more commands: after the last, or when the producer failed (the consumer stops waiting).
  void close();

  // ---- consumer ----
  /// The frame's fields, once begin() was called (or the feed was closed without it: then an
  /// empty frame). Its commands are read through wait_for only.
  const FrameWork& frame();
  /// How many commands the frame has (as begin() announced).
  std::size_t expected_commands();
  /// Command `c` once it is opened (its header fields; its renders through wait_render), or
  /// nullptr when the feed was closed without it. The reference stays valid for the feed's life;
  /// when command c + 1 is opened, command c's renders are all published (its tiles may still
  /// come: wait_tile).
  const CommandWork* wait_for(std::size_t c);
  /// Waits until command `c` (opened) is complete, or the feed closed without it: a dispatch
  /// is opened with its header before it runs and completed after (its content read then).
  void wait_complete(std::size_t c);
  /// Render `r` of command `c` (opened) once published, or nullptr when none follows: the
  /// command was completed with fewer renders, or its latest render is not partial (a render
  /// is partial exactly when another follows), or the feed closed without it.
  const RenderWork* wait_render(std::size_t c, std::size_t r);
  /// Tiles render `r` of command `c` has (as publish_render announced).
  std::size_t tile_count(std::size_t c, std::size_t r);
  /// Tile `i` of render `r` of command `c` once published, or nullptr when the feed was closed
  /// without it.
  const TileWork* wait_tile(std::size_t c, std::size_t r, std::size_t i);

  /// The whole frame's work (moved out of an open feed; a copy of a complete frame's), once the
  /// feed is closed and the consumer done with it.
  FrameWork take();
  /// Host wall seconds the consumer has spent blocked in frame(), expected_commands() and the
  /// wait_* calls, waiting for a piece not yet published (0 for a complete frame's feed): the
  /// part of the timing model's wall time in which the functional run, not the timing model,
  /// was behind.
  double consumer_wait_seconds() const;
  /// How many times the consumer has begun to wait (counted as it blocks, before it wakes).
  std::uint64_t consumer_waits() const;

 private:
  /// What of one command is published.
  struct Published {
    bool complete = false;
    std::vector<const RenderWork*> renders;
    std::vector<std::size_t> tiles;      ///< per render: announced
    std::vector<std::size_t> published;  ///< per render: published so far
  };
  void wait_begun(std::unique_lock<std::mutex>& lock);
  /// Blocks on changed_ until `ready()` (or the feed closes), adding the time blocked, if any, to
  /// wait_seconds_.
  template <class Ready>
  void wait_until(std::unique_lock<std::mutex>& lock, Ready ready);
  /// Open command `c`'s state (throws std::logic_error naming `what` if it is not open).
  Published& open_state(std::size_t c, const char* what);
  /// Registers every render and tile of a complete command.
  static Published complete(const CommandWork& cmd);
  mutable std::mutex mutex_;
  std::condition_variable changed_;
  FrameWork own_;                      ///< an open feed's frame (its commands vector never reallocates)
  const FrameWork* work_ = &own_;      ///< the frame read: own_ or a complete frame's
  std::vector<Published> state_;       ///< per command opened
  bool begun_ = false, closed_ = false;
  std::size_t expected_ = 0;
  double wait_seconds_ = 0;            ///< consumer_wait_seconds (under mutex_)
  std::uint64_t waits_ = 0;            ///< consumer_waits (under mutex_)
};

}  // namespace tbdr
