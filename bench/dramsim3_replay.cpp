// A replay front end for DRAMsim3 (built by bench/dram_vs_dramsim3.sh against the user's DRAMsim3
// build; not part of tbdrsim): reads a DRAMsim3 trace ("0xADDR READ|WRITE cycle" per line) and
// offers each transaction to DRAMsim3's MemorySystem from its cycle on, like dramsim3main's
// TraceBasedCPU, but with reads and writes in two queues of their own: a read the controller's
// read queue has room for enters even while a write waits for room in the full write buffer
// (tbdrsim's controller has a read and a write queue, each refusing only its own kind).
// dramsim3main's front end is in order and takes one transaction per cycle, so a write refused
// by a full write buffer holds every read behind it outside the controller, where the read
// latency DRAMsim3 measures (from AddTransaction to the data) does not see the wait.
//
// Prints key value lines: transactions, reads, the read latency measured from AddTransaction
// (mean, p99, in ns) and from the trace's cycle (the request's arrival), the cycles reads and
// writes waited outside the controller, and the last completion's cycle.
//   dramsim3_replay CONFIG.ini TRACE OUTPUT_DIR [in-order]
// "in-order" replays as dramsim3main does (one queue, one transaction per cycle), for comparison.
#include <algorithm>
#include <cinttypes>
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <deque>
#include <fstream>
#include <iostream>
#include <sstream>
#include <string>
#include <unordered_map>
#include <vector>

#include "dramsim3.h"

namespace {

struct Txn {
  std::uint64_t addr = 0;
  bool is_write = false;
  std::uint64_t cycle = 0;  // the trace's arrival cycle
};

double percentile(std::vector<std::uint64_t>& v, double p) {
  if (v.empty()) return 0;
  const std::size_t k = std::min(v.size() - 1, static_cast<std::size_t>(p * static_cast<double>(v.size())));
  std::nth_element(v.begin(), v.begin() + static_cast<std::ptrdiff_t>(k), v.end());
  return static_cast<double>(v[k]);
}

}  // namespace

int main(int argc, char** argv) {
  if (argc < 4) {
    std::fprintf(stderr, "usage: dramsim3_replay CONFIG.ini TRACE OUTPUT_DIR [in-order]\n");
    return 2;
  }
  const bool in_order = argc > 4 && std::strcmp(argv[4], "in-order") == 0;
  std::ifstream in(argv[2]);
  if (!in) {
    std::fprintf(stderr, "dramsim3_replay: cannot open %s\n", argv[2]);
    return 2;
  }
  std::deque<Txn> reads, writes, all;
  std::string addr, kind;
  std::uint64_t cycle = 0;
  std::size_t n = 0;
  while (in >> addr >> kind >> cycle) {
    Txn t{std::stoull(addr, nullptr, 16), kind == "WRITE", cycle};
    (in_order ? all : (t.is_write ? writes : reads)).push_back(t);
    ++n;
  }

  // Outstanding reads per address, oldest first: (add cycle, arrival cycle).
  std::unordered_map<std::uint64_t, std::deque<std::pair<std::uint64_t, std::uint64_t>>> pending;
  std::vector<std::uint64_t> lat_add, lat_arrival;
  std::uint64_t clk = 0, last_done = 0, read_wait = 0, write_wait = 0, reads_total = 0;
  auto on_read = [&](std::uint64_t a) {
    auto it = pending.find(a);
    if (it == pending.end() || it->second.empty()) return;
    const auto [added, arrived] = it->second.front();
    it->second.pop_front();
    lat_add.push_back(clk - added);
    lat_arrival.push_back(clk - arrived);
    last_done = std::max(last_done, clk);
  };
  auto on_write = [&](std::uint64_t) { last_done = std::max(last_done, clk); };
  dramsim3::MemorySystem* mem = dramsim3::GetMemorySystem(argv[1], argv[3], on_read, on_write);
  const double tck_ns = mem->GetTCK();

  auto offer = [&](std::deque<Txn>& q, bool one_per_cycle) {
    while (!q.empty() && q.front().cycle <= clk) {
      const Txn& t = q.front();
      if (!mem->WillAcceptTransaction(t.addr, t.is_write)) {
        (t.is_write ? write_wait : read_wait) += 1;
        return;
      }
      if (!t.is_write) {
        pending[t.addr].emplace_back(clk, t.cycle);
        ++reads_total;
      }
      mem->AddTransaction(t.addr, t.is_write);
      q.pop_front();
      if (one_per_cycle) return;
    }
  };
  while (!reads.empty() || !writes.empty() || !all.empty() || lat_add.size() < reads_total) {
    mem->ClockTick();
    if (in_order) {
      offer(all, true);
    } else {
      offer(reads, false);
      offer(writes, false);
    }
    ++clk;
    if (clk > (std::uint64_t{1} << 40)) break;
  }
  std::printf("front_end %s\ntransactions %zu\nreads %zu\n", in_order ? "in-order" : "split", n, lat_add.size());
  double sum_add = 0, sum_arr = 0;
  for (auto v : lat_add) sum_add += static_cast<double>(v);
  for (auto v : lat_arrival) sum_arr += static_cast<double>(v);
  const double k = lat_add.empty() ? 0 : tck_ns / static_cast<double>(lat_add.size());
  std::printf("read_latency_mean_ns %.3f\nread_latency_p99_ns %.3f\n", sum_add * k, percentile(lat_add, 0.99) * tck_ns);
  std::printf("read_latency_from_arrival_mean_ns %.3f\nread_latency_from_arrival_p99_ns %.3f\n", sum_arr * k,
              percentile(lat_arrival, 0.99) * tck_ns);
  std::printf("read_wait_cycles %" PRIu64 "\nwrite_wait_cycles %" PRIu64 "\nlast_completion_cycle %" PRIu64 "\n", read_wait,
              write_wait, last_done);
  delete mem;
  return 0;
}
