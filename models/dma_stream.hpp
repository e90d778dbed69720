#pragma once
// A DMA stream: how a unit moves a list of byte ranges of one traffic class to or from memory.
// The ranges are cut into requests at 4 KB boundaries (no AMBA AXI burst may cross a 4 KB address
// boundary: Arm, AMBA AXI protocol specification), a bounded number of them in flight; when the
// memory system pushes back the stream waits for its turn and retries.
#include <algorithm>
#include <cstdint>
#include <functional>
#include <utility>
#include <vector>

#include "kernel/event_queue.hpp"
#include "models/memory_system.hpp"

namespace tbdr {

/// Streams byte ranges of one traffic class through the memory system; calls `done` once every
/// byte has completed (reads back, writes accepted).
class DmaStream {
 public:
  /// Bytes per request: the 4 KB boundary no AXI burst crosses.
  static constexpr std::uint64_t kChunkBytes = 4096;

  DmaStream(EventQueue& eq, MemorySystem& mem, Client client, bool write, DramClass cls, std::uint32_t outstanding)
      : eq_(eq), mem_(mem), client_(client), write_(write), cls_(cls), outstanding_(outstanding) {}
  DmaStream(const DmaStream&) = delete;
  DmaStream& operator=(const DmaStream&) = delete;

  /// Where the stream puts itself once `done` has returned (when set): its owner reuses it
  /// through reset(), keeping its request list's storage.
  void recycle_into(std::vector<DmaStream*>* idle) { idle_ = idle; }
  /// A finished stream made ready to be filled again, as if constructed with these arguments.
  void reset(Client client, bool write, DramClass cls, std::uint32_t outstanding);

  /// Calls fn(addr, bytes) for each request the stream cuts [addr, addr + bytes) into.
  template <typename Fn>
  static void for_each_request(std::uint64_t addr, std::uint64_t bytes, Fn&& fn) {
    while (bytes > 0) {
      const std::uint64_t n = std::min<std::uint64_t>(bytes, kChunkBytes - (addr % kChunkBytes));
      fn(addr, static_cast<std::uint32_t>(n));
      addr += n;
      bytes -= n;
    }
  }
  /// Appends [addr, addr + bytes) to the stream (before start()).
  void add(std::uint64_t addr, std::uint64_t bytes);
  /// Starts issuing; `done` runs as an event once the last request completed (at once if empty).
  void start(std::function<void()> done);
  bool empty() const { return chunks_.empty(); }

 private:
  void pump();
  /// Runs `done` (moved out first: a stream it starts may be this one only after it returned),
  /// then offers the stream for reuse.
  void finish();
  EventQueue& eq_;
  MemorySystem& mem_;
  Client client_;
  bool write_;
  DramClass cls_;
  std::uint32_t outstanding_;
  std::vector<std::pair<std::uint64_t, std::uint32_t>> chunks_;
  std::size_t next_ = 0;
  std::size_t completed_ = 0;
  std::uint32_t in_flight_ = 0;
  bool waiting_ = false;
  std::function<void()> done_;
  std::vector<DmaStream*>* idle_ = nullptr;
};

}  // namespace tbdr
