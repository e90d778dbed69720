// Tests for the DMA stream (models/dma_stream): a unit's list of byte ranges moved through the
// memory system, and a finished stream reused for the next transfer (the timing model keeps few
// streams and refills them: reuse must not change when anything completes).
#include <gtest/gtest.h>

#include <cstdint>
#include <vector>

#include "kernel/event_queue.hpp"
#include "kernel/time.hpp"
#include "models/dma_stream.hpp"
#include "models/hw_config.hpp"
#include "models/memory_system.hpp"

namespace tbdr {
namespace {

/// The declared defaults: the tests compare two runs of the same transfers, not figures.
HwConfig stream_config() { return resolve_config({}, {}).hw; }

/// Ticks at which two transfers complete when the second follows the first's end on the same
/// memory system: the second in a stream of its own, or (`reuse`) in the first one, reset.
struct TwoTransfers {
  Tick first_done{-1};
  Tick second_done{-1};
  std::size_t idle_in_first_done = 99;  ///< streams offered for reuse while the first's `done` ran
  std::size_t idle_after = 0;           ///< streams offered for reuse at the end
};

TwoTransfers run_two(bool reuse) {
  const HwConfig hw = stream_config();
  EventQueue eq;
  MemorySystem mem(hw, eq);
  std::vector<DmaStream*> idle;
  DmaStream first(eq, mem, Client::Isp, false, DramClass::ParameterBuffer, 4);
  DmaStream second(eq, mem, Client::Isp, false, DramClass::ParameterBuffer, 4);
  first.recycle_into(&idle);
  second.recycle_into(&idle);
  TwoTransfers out;
  // 3 requests of 4 KB (the AXI boundary cuts 10 KB from 0x1800 into 2 KB + 4 KB + 4 KB), then
  // 2 more ranges elsewhere once the first has completed.
  first.add(0x1800, 10 * 1024);
  first.start([&] {
    out.first_done = eq.now();
    out.idle_in_first_done = idle.size();
    eq.schedule(eq.now(), [&] {
      DmaStream* s = &second;
      if (reuse) {
        EXPECT_EQ(idle.size(), 1u);  // the first, offered once its `done` returned
        s = idle.back();
        idle.pop_back();
        EXPECT_EQ(s, &first);
        s->reset(Client::Texture, false, DramClass::Textures, 2);
      } else {
        s->reset(Client::Texture, false, DramClass::Textures, 2);  // (a fresh stream, as constructed)
      }
      s->add(0x40000, 4096);
      s->add(0x80000, 256);
      s->start([&] { out.second_done = eq.now(); });
    });
  });
  eq.run();
  out.idle_after = idle.size();
  return out;
}

// The first transfer's `done` runs before the stream is offered for reuse (a stream started from
// inside it cannot be that one), and a reused stream completes its transfer at the tick a fresh
// one does: the memory system sees the same requests either way.
TEST(DmaStream, AFinishedStreamReusedCompletesAsAFreshOne) {
  const TwoTransfers fresh = run_two(false);
  const TwoTransfers reused = run_two(true);
  EXPECT_GT(fresh.first_done, Tick{0});
  EXPECT_GT(fresh.second_done, fresh.first_done);
  EXPECT_EQ(fresh.idle_in_first_done, 0u);
  EXPECT_EQ(reused.idle_in_first_done, 0u);
  EXPECT_EQ(reused.first_done, fresh.first_done);
  EXPECT_EQ(reused.second_done, fresh.second_done);
  // Fresh: both streams offered at the end; reused: the one stream, offered again.
  EXPECT_EQ(fresh.idle_after, 2u);
  EXPECT_EQ(reused.idle_after, 1u);
}

// An empty stream completes at once (as an event at the current tick) and is offered for reuse.
TEST(DmaStream, AnEmptyStreamCompletesAtOnceAndIsOfferedForReuse) {
  const HwConfig hw = stream_config();
  EventQueue eq;
  MemorySystem mem(hw, eq);
  std::vector<DmaStream*> idle;
  DmaStream s(eq, mem, Client::Compute, true, DramClass::Other, 1);
  s.recycle_into(&idle);
  int done = 0;
  s.start([&] { ++done; });
  EXPECT_EQ(done, 0);  // not inside start()
  eq.run();
  EXPECT_EQ(done, 1);
  EXPECT_EQ(eq.now(), Tick{0});
  ASSERT_EQ(idle.size(), 1u);
  EXPECT_EQ(idle[0], &s);
}

}  // namespace
}  // namespace tbdr
