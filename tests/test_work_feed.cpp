// The WorkFeed's contract (models/work_feed.hpp): the timing model waits for a command until the
// functional run publishes it (or opens it, then each render and tile), reads it in place while
// later ones are published, knows a pass has no more renders as soon as its render that is not
// partial is published, and stops waiting when the feed is closed, also when the functional run
// failed before any command.
// (That the timing it gives is the same as on a complete frame: tests/test_threads.cpp.)
#include <gtest/gtest.h>

#include <chrono>
#include <future>
#include <stdexcept>
#include <thread>

#include "models/hw_config.hpp"
#include "models/timing_model.hpp"
#include "models/work_feed.hpp"
#include "unit_fixture.hpp"

namespace tbdr {
namespace {

using namespace unit;

CommandWork named(const std::string& name) {
  CommandWork c;
  c.name = name;
  c.is_dispatch = true;
  c.compute_alu_ops = 1000;
  return c;
}

/// A fed frame's timing is the complete frame's: the same cycles, events, DRAM reads, commands.
void expect_same_timing(const TimingResult& fed, const TimingResult& whole) {
  EXPECT_GT(whole.frame_cycles, 0.0);
  EXPECT_EQ(fed.frame_cycles, whole.frame_cycles);
  EXPECT_EQ(fed.events, whole.events);
  EXPECT_EQ(fed.dram.total_read(), whole.dram.total_read());
  ASSERT_EQ(fed.commands.size(), whole.commands.size());
  for (std::size_t c = 0; c < fed.commands.size(); ++c) EXPECT_EQ(fed.commands[c].end_cycle, whole.commands[c].end_cycle);
}

TEST(WorkFeed, TheConsumerWaitsForEachCommandAndStopsWhenClosed) {
  WorkFeed feed;
  // The consumer starts first and waits: for the frame, then command by command.
  std::future<std::vector<std::string>> names = std::async(std::launch::async, [&feed] {
    std::vector<std::string> seen;
    EXPECT_EQ(feed.frame().tiles_x, 7);
    EXPECT_EQ(feed.expected_commands(), 3u);
    for (std::size_t c = 0;; ++c) {
      const CommandWork* cmd = feed.wait_for(c);
      if (!cmd) break;
      seen.push_back(cmd->name);
    }
    return seen;
  });
  FrameWork frame;
  frame.tiles_x = 7;
  frame.commands.push_back(named("ignored"));  // begin() takes the frame's fields only
  feed.begin(frame, 3);
  feed.publish(named("a"));
  std::this_thread::sleep_for(std::chrono::milliseconds(20));  // the consumer is waiting meanwhile
  feed.publish(named("b"));
  feed.publish(named("c"));
  EXPECT_THROW(feed.publish(named("d")), std::logic_error) << "more commands than announced: a reallocation would move them";
  feed.close();
  EXPECT_EQ(names.get(), (std::vector<std::string>{"a", "b", "c"}));
  const FrameWork back = feed.take();
  ASSERT_EQ(back.commands.size(), 3u);
  EXPECT_EQ(back.commands[1].name, "b");
  EXPECT_EQ(back.tiles_x, 7);
}

TEST(WorkFeed, OnlyTheTimeTheConsumerIsBlockedCountsAsWaiting) {
  // A complete frame's feed and an open one whose pieces are all published before they are asked
  // for: nothing waited, exactly 0.
  FrameWork frame;
  frame.tiles_x = 1;
  frame.commands = {named("dispatch0.a")};
  WorkFeed complete(frame);
  EXPECT_EQ(complete.expected_commands(), 1u);
  ASSERT_NE(complete.wait_for(0), nullptr);
  EXPECT_EQ(complete.consumer_wait_seconds(), 0.0);
  WorkFeed ahead;
  ahead.begin(frame, 1);
  ahead.publish(named("a"));
  ahead.close();
  ASSERT_NE(ahead.wait_for(0), nullptr);
  EXPECT_EQ(ahead.wait_for(1), nullptr);
  EXPECT_EQ(ahead.consumer_wait_seconds(), 0.0);

  // The consumer asks first and blocks until the producer publishes, which it does only once the
  // consumer has begun to wait (consumer_waits, counted before it blocks): that time counts (more
  // than 0), and no more than the call lasted. No clock decides the order.
  WorkFeed feed;
  feed.begin(frame, 1);
  std::future<double> call_seconds = std::async(std::launch::async, [&feed] {
    const auto from = std::chrono::steady_clock::now();
    EXPECT_NE(feed.wait_for(0), nullptr);
    return std::chrono::duration<double>(std::chrono::steady_clock::now() - from).count();
  });
  while (feed.consumer_waits() == 0) std::this_thread::yield();
  feed.publish(named("a"));
  feed.close();
  const double call = call_seconds.get();
  EXPECT_EQ(feed.consumer_waits(), 1u);
  EXPECT_GT(feed.consumer_wait_seconds(), 0.0);
  EXPECT_LE(feed.consumer_wait_seconds(), call);
}

TEST(WorkFeed, TheTimingModelStopsWhenTheFunctionalRunFailsBeforeAnyCommand) {
  WorkFeed feed;
  const HwConfig hw = resolve_config({}, {}).hw;
  std::future<TimingResult> timed = std::async(std::launch::async, [&] { return run_timing(hw, feed); });
  feed.close();  // as simulate_frame does when it throws before begin()
  const TimingResult r = timed.get();
  EXPECT_EQ(r.frame_cycles, 0.0);
  EXPECT_TRUE(r.commands.empty());
}

TEST(WorkFeed, TheTimingModelOfAFedFrameIsTheCompleteFramesOne) {
  // Two dispatches, the second published while the timing model waits for it.
  FrameWork frame;
  frame.tiles_x = 1;
  frame.commands = {named("dispatch0.a"), named("dispatch1.b")};
  frame.commands[1].compute_alu_ops = 50000;
  frame.commands[1].read_bytes[static_cast<std::size_t>(DramClass::Other)] = 8192;
  const HwConfig hw = resolve_config({}, {}).hw;
  const TimingResult whole = run_timing(hw, frame);

  WorkFeed feed;
  std::future<TimingResult> timed = std::async(std::launch::async, [&] { return run_timing(hw, feed); });
  feed.begin(frame, 2);
  feed.publish(CommandWork(frame.commands[0]));
  std::this_thread::sleep_for(std::chrono::milliseconds(20));
  feed.publish(CommandWork(frame.commands[1]));
  feed.close();
  expect_same_timing(timed.get(), whole);
}

/// A pass of two renders (a partial one, then the last) of 4 tiles each with loads, stores and
/// texture lines, then a dispatch reading what the pass stored.
FrameWork pass_and_dispatch() {
  auto tile = [](int tx, int ty, std::uint64_t alu) {
    TileWork t = tile_work(tx, ty, 40, 1024, alu, 512);
    t.load_bytes[static_cast<std::size_t>(DramClass::Color)] = 4096;
    t.store_bytes[static_cast<std::size_t>(DramClass::Color)] = 4096;
    for (std::uint64_t l = 0; l < 16; ++l) t.texture_lines.push_back((static_cast<std::uint64_t>(ty * 2 + tx) * 8 + l) * 64);
    return t;
  };
  std::vector<RenderWork> renders;
  renders.push_back(render_work({tile(0, 0, 9000), tile(1, 0, 3000), tile(0, 1, 5000), tile(1, 1, 7000)}, binning_work(2000), true));
  renders.push_back(render_work({tile(1, 1, 4000), tile(0, 1, 8000), tile(1, 0, 2000), tile(0, 0, 6000)}, binning_work(1000), false));
  FrameWork f = frame_work({pass_work("pass0.main", std::move(renders)), named("dispatch1.after")});
  f.commands[1].read_bytes[static_cast<std::size_t>(DramClass::Color)] = 16384;
  f.texture_bytes = 1 << 20;
  return f;
}

TEST(WorkFeed, APassFedRenderByRenderAndTileByTileTimesAsTheCompleteFrame) {
  const FrameWork frame = pass_and_dispatch();
  const HwConfig hw = resolve_config({}, {}).hw;
  const TimingResult whole = run_timing(hw, frame);

  WorkFeed feed;
  std::future<TimingResult> timed = std::async(std::launch::async, [&] { return run_timing(hw, feed); });
  feed.begin(frame, 2);
  CommandWork header = frame.commands[0];
  header.renders.clear();
  CommandWork& live = feed.open(std::move(header));
  for (const RenderWork& r : frame.commands[0].renders) {
    RenderWork& rw = live.renders.emplace_back();
    rw.binning = r.binning;
    rw.partial = r.partial;
    rw.tiles.reserve(r.tiles.size());
    feed.publish_render(0, r.tiles.size());
    for (const TileWork& t : r.tiles) {
      std::this_thread::sleep_for(std::chrono::milliseconds(5));  // the timing model waits for tiles meanwhile
      rw.tiles.push_back(t);
      feed.publish_tiles(0, rw.tiles.size());
    }
  }
  feed.close_command(0);
  feed.publish(CommandWork(frame.commands[1]));
  feed.close();
  const TimingResult fed = timed.get();
  expect_same_timing(fed, whole);
  EXPECT_EQ(fed.commands[0].binning_end_cycle, whole.commands[0].binning_end_cycle);
  EXPECT_EQ(fed.tiles.size(), whole.tiles.size());
}

/// A producer replaying `frame`'s commands into a feed piece by piece, as the functional run
/// does, with the timing model reading the feed on its own thread; the timing of the complete
/// frame beside it.
struct Replay {
  explicit Replay(const FrameWork& f) : frame(f), whole(run_timing(hw, f)) {
    timed = std::async(std::launch::async, [this] { return run_timing(hw, feed); });
    feed.begin(frame, frame.commands.size());
  }
  /// Closes the feed; the fed timing must be the complete frame's.
  void expect_same_as_complete() {
    feed.close();
    expect_same_timing(timed.get(), whole);
  }
  const FrameWork& frame;
  const HwConfig hw = resolve_config({}, {}).hw;
  const TimingResult whole;
  WorkFeed feed;
  std::future<TimingResult> timed;
  /// Opens pass `c` with its header (no renders).
  CommandWork& open(std::size_t c) {
    CommandWork header = frame.commands[c];
    header.renders.clear();
    return feed.open(std::move(header));
  }
  /// Publishes render `r` of open command `c` (`live`), binned, its tiles to come.
  RenderWork& bin(CommandWork& live, std::size_t c, std::size_t r) {
    const RenderWork& src = frame.commands[c].renders[r];
    RenderWork& rw = live.renders.emplace_back();
    rw.binning = src.binning;
    rw.partial = src.partial;
    rw.tiles.reserve(src.tiles.size());
    feed.publish_render(c, src.tiles.size());
    return rw;
  }
  /// Publishes the tiles of render `r` of command `c` into `rw` one by one (the timing model
  /// waits for them meanwhile).
  void tiles(RenderWork& rw, std::size_t c, std::size_t r) {
    for (const TileWork& t : frame.commands[c].renders[r].tiles) {
      std::this_thread::sleep_for(std::chrono::milliseconds(2));
      rw.tiles.push_back(t);
      feed.publish_tiles(c, rw.tiles.size());
    }
  }
};

// The functional run bins a pass before the tiles of the pass before it (command_processor.cpp):
// the next pass is opened and its renders published while the previous one's last render still
// renders. The timing model reads the next pass's binning meanwhile and times the frame as the
// complete one.
TEST(WorkFeed, APassOpenedWhileThePreviousOnesTilesStillComeTimesAsTheCompleteFrame) {
  FrameWork frame = pass_and_dispatch();
  CommandWork second = frame.commands[0];
  second.name = "pass1.next";
  for (RenderWork& r : second.renders) {
    for (TileWork& t : r.tiles) t.load_bytes[static_cast<std::size_t>(DramClass::Color)] = 0;
  }
  frame.commands.insert(frame.commands.begin() + 1, second);
  Replay replay(frame);
  WorkFeed& feed = replay.feed;
  CommandWork& first = replay.open(0);
  replay.tiles(replay.bin(first, 0, 0), 0, 0);  // the partial render: binned and rendered before the last is binned
  RenderWork& last = replay.bin(first, 0, 1);
  EXPECT_THROW(feed.publish(CommandWork(frame.commands[2])), std::logic_error) << "a complete command after an open one";
  CommandWork& next = replay.open(1);  // binned ahead: pass 0's last render has not rendered yet
  RenderWork& next0 = replay.bin(next, 1, 0);
  EXPECT_THROW(replay.open(2), std::logic_error) << "pass 1 is open with renders to come";
  EXPECT_THROW(feed.close_command(1), std::logic_error) << "closed before the command before it";
  EXPECT_NE(feed.wait_render(1, 0), nullptr) << "the consumer has the next pass's binning now";
  replay.tiles(last, 0, 1);
  feed.close_command(0);
  replay.tiles(next0, 1, 0);
  replay.tiles(replay.bin(next, 1, 1), 1, 1);
  feed.close_command(1);
  feed.publish(CommandWork(frame.commands[2]));
  replay.expect_same_as_complete();
}

// A pass binned past a dispatch (command_processor.cpp: a pass, a dispatch reading it, a pass):
// the dispatch is opened with its header before the pass before it renders and filled and closed
// after, and the pass after it is opened and binned before either. The timing model takes the
// pass after the dispatch (its binning) while the first pass's tiles still come, waits for the
// dispatch's content only when its fragment job starts, and times the frame as the complete one.
TEST(WorkFeed, APassBinnedPastAnOpenDispatchTimesAsTheCompleteFrame) {
  FrameWork frame = pass_and_dispatch();  // pass0.main, dispatch1.after
  CommandWork last = frame.commands[0];
  last.name = "pass2.after_dispatch";
  last.read_bytes[static_cast<std::size_t>(DramClass::LightLists)] = 8192;  // what the dispatch wrote: filled late
  frame.commands[1].write_bytes[static_cast<std::size_t>(DramClass::LightLists)] = 8192;
  frame.commands.push_back(last);
  Replay replay(frame);
  WorkFeed& feed = replay.feed;
  CommandWork& first = replay.open(0);
  replay.tiles(replay.bin(first, 0, 0), 0, 0);
  RenderWork& first_last = replay.bin(first, 0, 1);
  // The dispatch's header only: its name and kind.
  CommandWork dispatch_header;
  dispatch_header.name = frame.commands[1].name;
  dispatch_header.is_dispatch = true;
  dispatch_header.depends_on_previous = frame.commands[1].depends_on_previous;
  CommandWork& dispatch = feed.open(std::move(dispatch_header));
  // The pass after it, opened and binned (its partial render too) before the first pass's tiles.
  CommandWork header = frame.commands[2];
  header.renders.clear();
  header.read_bytes = {};
  CommandWork& after = feed.open(std::move(header));
  RenderWork& after0 = replay.bin(after, 2, 0);
  EXPECT_THROW(feed.close_command(1), std::logic_error) << "the dispatch closed before the pass before it";
  replay.tiles(first_last, 0, 1);
  feed.close_command(0);
  std::this_thread::sleep_for(std::chrono::milliseconds(20));  // the timing model waits for the dispatch's content meanwhile
  // The dispatch has run: its content, and what the pass after it reads of it, then the dispatch closed.
  const CommandWork& ran = frame.commands[1];
  dispatch.compute_alu_ops = ran.compute_alu_ops;
  dispatch.read_bytes = ran.read_bytes;
  dispatch.write_bytes = ran.write_bytes;
  after.read_bytes = frame.commands[2].read_bytes;
  feed.close_command(1);
  replay.tiles(after0, 2, 0);
  replay.tiles(replay.bin(after, 2, 1), 2, 1);
  feed.close_command(2);
  replay.expect_same_as_complete();
}

TEST(WorkFeed, OpenDispatchesMayStandBetweenTheLastPassBinnedAheadAndTheNext) {
  WorkFeed feed;
  FrameWork frame;
  feed.begin(frame, 5);
  CommandWork& pass = feed.open(CommandWork{});
  pass.renders.emplace_back().partial = false;
  feed.publish_render(0, 0);
  CommandWork d;
  d.is_dispatch = true;
  feed.open(CommandWork(d));
  feed.open(CommandWork(d));  // any number of open dispatches
  CommandWork& next = feed.open(CommandWork{});  // a pass beyond them
  EXPECT_THROW(feed.open(CommandWork(d)), std::logic_error) << "the pass just opened has renders to come";
  next.renders.emplace_back().partial = false;
  feed.publish_render(3, 0);
  EXPECT_THROW(feed.open(CommandWork{}), std::logic_error) << "two passes open already";
  EXPECT_THROW(feed.close_command(2), std::logic_error) << "closed before the commands before it";
  feed.close_command(0);
  feed.close_command(1);
  feed.close_command(2);
  feed.close_command(3);
  feed.close();
}

TEST(WorkFeed, ARenderThatIsNotPartialIsItsPassLastBeforeThePassIsClosed) {
  WorkFeed feed;
  FrameWork frame;
  feed.begin(frame, 1);
  CommandWork& live = feed.open(CommandWork{});
  live.renders.emplace_back().partial = true;
  feed.publish_render(0, 0);
  live.renders.emplace_back().partial = false;
  feed.publish_render(0, 0);
  // The consumer learns there is no third render without waiting for close_command (this thread
  // would wait forever otherwise).
  EXPECT_NE(feed.wait_render(0, 1), nullptr);
  EXPECT_EQ(feed.wait_render(0, 2), nullptr);
  live.renders.emplace_back();
  EXPECT_THROW(feed.publish_render(0, 0), std::logic_error) << "no render follows the last";
}

TEST(WorkFeed, TheProducerMustKeepItsTilesInPlaceAndPublishThemAll) {
  WorkFeed feed;
  FrameWork frame;
  feed.begin(frame, 2);
  CommandWork& live = feed.open(CommandWork{});
  EXPECT_THROW(feed.open(CommandWork{}), std::logic_error) << "the previous command is open with renders to come";
  RenderWork& rw = live.renders.emplace_back();
  EXPECT_THROW(feed.publish_render(0, 3), std::logic_error) << "no room reserved: its tiles could move";
  rw.tiles.reserve(3);
  feed.publish_render(0, 3);
  EXPECT_THROW(feed.publish_tiles(0, 4), std::logic_error) << "more tiles than announced";
  EXPECT_THROW(feed.publish_tiles(1, 1), std::logic_error) << "no command 1 is open";
  rw.tiles.emplace_back();
  rw.tiles.emplace_back();
  feed.publish_tiles(0, 2);
  feed.publish_tiles(0, 1);  // a thread reporting out of turn: the count stays 2
  EXPECT_EQ(feed.wait_tile(0, 0, 0), rw.tiles.data());
  EXPECT_EQ(feed.wait_tile(0, 0, 1), rw.tiles.data() + 1);
  EXPECT_THROW(feed.close_command(0), std::logic_error) << "a tile not published";
  feed.close();
  EXPECT_EQ(feed.wait_tile(0, 0, 2), nullptr) << "a closed feed ends the wait";
}

}  // namespace
}  // namespace tbdr
