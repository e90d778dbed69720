// The WorkFeed's contract (models/work_feed.hpp): the timing model waits for a command until the
// functional run publishes it, reads it in place while later ones are published, and stops
// waiting when the feed is closed, also when the functional run failed before any command.
// (That the timing it gives is the same as on a complete frame: tests/test_threads.cpp.)
#include <gtest/gtest.h>

#include <chrono>
#include <future>
#include <stdexcept>
#include <thread>

#include "models/hw_config.hpp"
#include "models/timing_model.hpp"
#include "models/work_feed.hpp"

namespace tbdr {
namespace {

CommandWork named(const std::string& name) {
  CommandWork c;
  c.name = name;
  c.is_dispatch = true;
  c.compute_alu_ops = 1000;
  return c;
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
  const TimingResult fed = timed.get();
  EXPECT_GT(whole.frame_cycles, 0.0);
  EXPECT_EQ(fed.frame_cycles, whole.frame_cycles);
  EXPECT_EQ(fed.events, whole.events);
  ASSERT_EQ(fed.commands.size(), 2u);
  EXPECT_EQ(fed.commands[1].end_cycle, whole.commands[1].end_cycle);
}

}  // namespace
}  // namespace tbdr
