#pragma once
// The external DRAM: channels x banks, one row buffer per bank under an open-page policy, read and
// write queues per channel with an FR-FCFS scheduler (rows are opened ahead for the oldest
// requests, column commands go to the oldest row hit the data bus can take; writes drained in
// bursts between watermarks), JEDEC-style timing (tRCD, tRP, RL, tRAS, tWR, tRRD, tFAW, tWTR,
// read-to-write turnaround, all-bank refresh every tREFI for tRFC, bank groups with tCCD_L and
// tCCD_S, data-bus time from the channel bandwidth, controller latency) and energy per bit and per activate (DRAMPower-style figures from
// [energy]) plus background power (active / precharge standby) and refresh energy from [dram].
// See docs/memory-model.md for the equations.
//
// Two ways in:
//  - timed: enqueue() a line-sized request; the controller schedules it on the event queue and
//    calls its on_complete at the exact tick the data (or write acknowledgement) is back. A full
//    queue refuses the request (backpressure): the caller keeps it and retries, e.g. from the
//    space callback.
//  - functional: access_functional() updates the row buffers and every byte, row and energy count
//    without timing, for the fast path.
#include <array>
#include <cstdint>
#include <functional>
#include <memory>
#include <string>
#include <string_view>
#include <vector>

#include "models/busy_intervals.hpp"
#include "models/hw_config.hpp"
#include "trace/traffic.hpp"
#include "kernel/event_queue.hpp"
#include "kernel/run_loop.hpp"
#include "kernel/slot_pool.hpp"
#include "kernel/stats.hpp"
#include "kernel/time.hpp"

namespace tbdr {

class DramObserver;  // models/dram_observer.hpp

/// One transfer between the chip and DRAM (normally one cache line; never crossing a row).
struct DramRequest {
  std::uint64_t addr = 0;
  std::uint32_t bytes = 0;  ///< rounded up to whole bursts by the controller
  bool is_write = false;
  DramClass cls = DramClass::Other;
  EventCallback on_complete;  ///< run at the completion tick (Priority::DramResponse); may be empty
  /// Line transfers merged into this request (a burst chain of consecutive lines of one row).
  /// The controller queues and schedules it as one entry; the statistics count each line as a
  /// request, the first with the row outcome found, the others as row hits.
  std::uint32_t lines = 1;
  /// Instead of an on_complete event at the completion tick: report the request to the schedule
  /// callback (with `tag`) as soon as the controller has scheduled its data, so the requester
  /// learns every line's arrival without an event per request (see set_schedule_callback()).
  bool report_when_scheduled = false;
  std::uint64_t tag = 0;
};

/// When the controller has scheduled a request's data: its bursts occupy the data bus from
/// `data_start` to `data_end` (evenly, in address order) and each part reaches the requester
/// `return_latency` after its last burst.
struct DramSchedule {
  Tick data_start{0};
  Tick data_end{0};
  Tick return_latency{0};
};

/// Where an address lands in the DRAM.
struct DramCoord {
  std::uint32_t channel = 0;
  std::uint32_t bank = 0;
  std::uint64_t row = 0;
  std::uint32_t column = 0;  ///< byte offset within the row
};

/// The DRAM timing the controller uses, converted from the [dram] parameters.
struct DramTiming {
  std::int64_t t_rcd_cycles = 0;  ///< activate -> column command
  std::int64_t t_rp_cycles = 0;   ///< precharge -> activate
  std::int64_t t_cl_cycles = 0;   ///< column command -> first data (reads and writes)
  std::int64_t t_ras_cycles = 0;  ///< activate -> precharge
  std::int64_t t_wr_cycles = 0;   ///< end of write data -> precharge
  std::int64_t t_rrd_cycles = 0;  ///< activate -> activate (any two banks of a channel)
  std::int64_t t_faw_cycles = 0;  ///< activate -> the fourth activate after it
  std::int64_t t_wtr_cycles = 0;  ///< end of write data -> read command
  Tick t_rtw{0};                  ///< end of read data -> start of write data
  std::uint32_t bank_groups = 1;  ///< bank b is in group b mod bank_groups
  Tick t_ccd_l{0};                ///< burst start to burst start, same bank group (0: none)
  Tick t_ccd_s{0};                ///< burst start to burst start, any two groups (0: none)
  std::int64_t t_refi_cycles = 0; ///< refresh interval per channel (0: no refresh)
  std::int64_t t_rfc_cycles = 0;  ///< refresh cycle time
  Tick controller{0};             ///< controller + interconnect latency, each way
  double burst_ps = 0;            ///< data-bus time of one burst on one channel
  Tick transfer(std::uint32_t bursts) const;
};

/// How a request found its bank's row buffer.
enum class RowOutcome : std::uint8_t {
  Hit,       ///< the row was open: column command only
  Empty,     ///< no row open: activate + column
  Conflict,  ///< another row open: precharge + activate + column
};

/// DRAM energy in pJ of the given transfers and activates, with the [energy] unit costs:
/// read_bits*read_pj + write_bits*write_pj + (read_bits+write_bits)*io_pj + activates*act_nj*1000.
/// The single formula behind every DRAM energy statistic (total, per class, per component).
double dram_energy_pj(const EnergyParams& e, std::uint64_t read_bytes, std::uint64_t write_bytes,
                      std::uint64_t activates);

// Declared once: X(type, member = stored name, unit, Sum | Gauge, description).
#define TBDR_DRAM_STATS(X) \
  X(Counter, reads, "requests", Sum, "Read requests (line transfers) served") \
  X(Counter, writes, "requests", Sum, "Write requests (line transfers) served") \
  X(Counter, queue_entries_served, "entries", Sum, "Queue entries served: requests, a burst chain of lines counting once") \
  X(Counter, read_bytes, "bytes", Sum, "Bytes read (whole bursts)") \
  X(Counter, write_bytes, "bytes", Sum, "Bytes written (whole bursts)") \
  X(Counter, row_hits, "requests", Sum, "Requests that found their row open") \
  X(Counter, row_misses, "requests", Sum, "Requests that needed an activate (empty + conflict)") \
  X(Counter, row_misses_empty, "requests", Sum, "Row misses to a bank with no open row") \
  X(Counter, row_conflicts, "requests", Sum, "Row misses that closed another open row") \
  X(Counter, activates, "commands", Sum, "Activate commands") \
  X(Counter, precharges, "commands", Sum, "Precharge commands") \
  X(Counter, queue_full_rejections, "requests", Sum, "Requests refused because their queue was full") \
  X(Counter, completed, "requests", Sum, "Timed requests completed") \
  X(Counter, read_latency_total_ps, "ps", Sum, "Sum over timed read lines of enqueue to the line's data back") \
  X(Counter, refreshes, "commands", Sum, "All-bank refreshes (each channel every dram.t_refi_ns, timed path)") \
  X(Counter, read_to_write_turnarounds, "switches", Sum, "Data bus switches from read to write data (pay dram.t_rtw_ns)") \
  X(Counter, write_to_read_turnarounds, "switches", Sum, "Data bus switches from write to read data (pay dram.t_wtr_ns + RL)") \
  X(Counter, activates_delayed_rrd_faw, "commands", Sum, "Activates that tRRD or tFAW pushed later than their bank allowed") \
  X(Counter, powerdown_exits, "exits", Sum, "Requests that found their channel in power-down (dram.powerdown_after_ns) and waited tXP") \
  X(Counter, bursts_delayed_ccd, "requests", Sum, "Queue entries whose data tCCD_L (same bank group) or tCCD_S pushed past the data bus") \
  X(Accumulator, row_hit_rate, "ratio", Derived, "Row hits / requests") \
  X(Accumulator, avg_read_latency_ns, "ns", Derived, "Mean timed read latency per line, enqueue to data back") \
  X(Accumulator, achieved_bandwidth_gbps, "GB/s", Derived, "Timed bytes / (last completion - first enqueue)") \
  X(Accumulator, peak_bandwidth_gbps, "GB/s", Gauge, "Peak data bandwidth: dram.clock_mhz x transfers_per_clock x bus_width_bits / 8 x channels") \
  X(Accumulator, energy_read_pj, "pJ", Sum, "Read core energy: read bits x dram_read_pj_per_bit") \
  X(Accumulator, energy_write_pj, "pJ", Sum, "Write core energy: write bits x dram_write_pj_per_bit") \
  X(Accumulator, energy_io_pj, "pJ", Sum, "I/O energy: (read + write bits) x dram_io_pj_per_bit") \
  X(Accumulator, energy_activate_pj, "pJ", Sum, "Activates x dram_activate_precharge_nj x 1000") \
  X(Accumulator, energy_background_pj, "pJ", Sum, "Standby: per channel active_standby_mw x time with a row open + precharge_standby_mw x time all precharged, power-down time at the power-down figures") \
  X(Accumulator, energy_refresh_pj, "pJ", Sum, "Refreshes x dram.refresh_nj x 1000") \
  X(Accumulator, energy_dynamic_pj, "pJ", Sum, "Read + write + I/O + activate/precharge (what the traffic classes share)") \
  X(Accumulator, energy_pj, "pJ", Sum, "Total DRAM energy (dynamic + background + refresh)") \
  X(Accumulator, energy_per_bit_pj, "pJ/bit", Derived, "Total DRAM energy / bits transferred")
/// Whole-DRAM statistics.
struct DramStats {
  TBDR_STATS(TBDR_DRAM_STATS)
};

// Declared once: X(type, member = stored name, unit, Sum | Gauge, description).
#define TBDR_DRAM_CHANNEL_STATS(X) \
  X(Counter, reads, "requests", Sum, "Read requests served") \
  X(Counter, writes, "requests", Sum, "Write requests served") \
  X(Counter, bytes, "bytes", Sum, "Bytes transferred (both directions)") \
  X(Counter, row_hits, "requests", Sum, "Requests that found their row open") \
  X(Counter, row_misses, "requests", Sum, "Requests that needed an activate") \
  X(Counter, activates, "commands", Sum, "Activate commands") \
  X(Counter, precharges, "commands", Sum, "Precharge commands") \
  X(Counter, busy_ps, "ps", Sum, "Time the data bus was transferring") \
  X(Counter, read_queue_full, "requests", Sum, "Reads refused: read queue full") \
  X(Counter, write_queue_full, "requests", Sum, "Writes refused: write queue full") \
  X(Counter, write_drains, "drains", Sum, "Times the write queue reached the high watermark") \
  X(Counter, refreshes, "commands", Sum, "All-bank refreshes") \
  X(Counter, precharged_ps, "ps", Sum, "Time every bank was precharged (precharge standby), up to the last statistics update") \
  X(Counter, powerdown_ps, "ps", Sum, "Time in power-down (active or precharge), up to the last statistics update") \
  X(Accumulator, read_queue_occupancy_avg, "requests", Derived, "Time-averaged read queue occupancy (from tick 0)") \
  X(Accumulator, write_queue_occupancy_avg, "requests", Derived, "Time-averaged write queue occupancy (from tick 0)") \
  X(Accumulator, utilization, "ratio", Derived, "busy_ps / elapsed ps (from tick 0)")
/// Statistics of one DRAM channel.
struct DramChannelStats {
  TBDR_STATS(TBDR_DRAM_CHANNEL_STATS)
};

// Declared once: X(type, member = stored name, unit, Sum | Gauge, description).
#define TBDR_DRAM_CLASS_STATS(X) \
  X(Counter, reads, "requests", Sum, "Read requests of this class") \
  X(Counter, writes, "requests", Sum, "Write requests of this class") \
  X(Counter, read_bytes, "bytes", Sum, "DRAM bytes read for this traffic class") \
  X(Counter, write_bytes, "bytes", Sum, "DRAM bytes written for this traffic class") \
  X(Counter, activates, "commands", Sum, "Activates caused by requests of this class") \
  X(Accumulator, energy_pj, "pJ", Sum, "DRAM energy of this class (its bytes and its activates)")
/// DRAM statistics of one traffic class.
struct DramClassStats {
  TBDR_STATS(TBDR_DRAM_CLASS_STATS)
};

/// The DRAM devices and their memory controller.
/// The DRAM's statistics at one moment (Dram::snapshot), with the scope its rows take.
struct DramSnapshot {
  std::string scope;  ///< "mem/dram"; a channel's rows: scope + ".ch<i>", a class's: scope + ".class." + class
  DramStats stats;
  std::vector<DramChannelStats> channels;
  std::array<DramClassStats, kDramClassCount> classes;
};

class Dram final : public Unit {
 public:
  /// FR-FCFS starvation cap: once this many younger requests were served while the oldest one
  /// waited for its row, the oldest may close a row that younger requests still want. The cap of
  /// Ramulator's FRFCFS_Cap scheduler (src/Scheduler.h: cap = 16).
  static constexpr std::uint32_t kStarvationCap = 16;
  /// Most banks per channel: the scheduler keeps one bit per bank in a 64-bit mask.
  static constexpr std::int64_t kMaxBanks = 64;

  /// Validates the parameters (std::invalid_argument on an inconsistent geometry).
  Dram(const DramParams& p, const EnergyParams& e, EventQueue& eq, std::string scope = "dram");
  Dram(const Dram&) = delete;
  Dram& operator=(const Dram&) = delete;

  /// Timed: queues a request; false (and nothing changes but the rejection count) when its
  /// channel's read or write queue is full. The request enters the queue now, is eligible for
  /// scheduling after the controller latency, and completes controller latency after its data.
  /// Throws std::invalid_argument for a request of 0 bytes or one that crosses a row.
  /// `req` is moved from only when it is accepted: on false the caller still owns it and retries.
  bool enqueue(DramRequest&& req);
  /// Whether enqueue() would accept a request for `addr` now.
  bool can_accept(std::uint64_t addr, bool is_write) const;
  /// Tests: each scheduler step also finds the banks holding an arrived row hit by a second pass
  /// over the queue after its decisions, and throws std::logic_error where that differs from
  /// what the step derived from its single pass (Dram::wakeup).
  void set_verify_scheduler(bool on) { verify_scheduler_ = on; }
  /// Called (after the scheduler step that freed it) whenever a queue slot frees on a channel.
  void set_space_callback(std::function<void(std::uint32_t channel)> cb) { space_cb_ = std::move(cb); }
  /// Called, for requests with report_when_scheduled, at the moment their column command is
  /// scheduled (a tick before their data is back); such requests schedule no completion event.
  void set_schedule_callback(std::function<void(std::uint64_t tag, const DramSchedule&)> cb) {
    schedule_cb_ = std::move(cb);
  }
  /// Reports every accepted request and every command to `o` (nullptr: none; not owned).
  void set_observer(DramObserver* o) { observer_ = o; }

  /// Functional: the same row-buffer and statistics update as a timed request, without timing.
  RowOutcome access_functional(std::uint64_t addr, std::uint32_t bytes, bool is_write, DramClass cls,
                               std::uint32_t lines = 1);

  /// Address mapping.
  DramCoord map(std::uint64_t addr) const;
  std::uint32_t channel_of(std::uint64_t addr) const { return map(addr).channel; }
  /// Bytes a request of `bytes` transfers: whole bursts.
  std::uint32_t transfer_bytes(std::uint32_t bytes) const {
    return static_cast<std::uint32_t>((bytes + burst_bytes_ - 1) / burst_bytes_ * burst_bytes_);
  }

  const DramTiming& timing() const { return timing_; }
  const ClockDomain& clock() const { return clock_; }
  DramMapping mapping() const { return mapping_; }
  std::uint32_t channels() const { return static_cast<std::uint32_t>(channels_.size()); }
  std::uint32_t banks() const { return banks_; }
  std::uint64_t row_bytes() const { return row_bytes_; }
  std::uint32_t burst_bytes() const { return burst_bytes_; }
  /// Most lines one request may carry: a burst chain occupies one queue entry per line.
  std::uint32_t max_request_lines() const { return static_cast<std::uint32_t>(std::min(read_cap_, write_cap_)); }
  std::size_t read_queue_size(std::uint32_t channel) const { return channels_[channel].readq.size(); }
  std::size_t write_queue_size(std::uint32_t channel) const { return channels_[channel].writeq.size(); }
  /// Requests accepted (timed) and not yet completed.
  std::uint64_t in_flight() const { return in_flight_; }

  const DramStats& stats() const { return stats_; }
  const DramChannelStats& channel_stats(std::uint32_t c) const { return channels_[c].stats; }
  /// When channel `c`'s data bus transferred, in ps (at most kFrameBusyIntervals intervals).
  const BusyIntervals& bus_busy(std::uint32_t c) const { return channels_[c].bus_busy; }
  const DramClassStats& class_stats(DramClass c) const { return class_stats_[static_cast<std::size_t>(c)]; }
  /// Bytes per class so far, in the shape the rest of the simulator uses.
  DramTraffic traffic() const;
  /// Energy so far: dynamic (the dram_energy_pj formula) + background + refresh up to now().
  double energy_pj() const;
  /// Dynamic energy of one class (its bytes and its activates; background is not split by class).
  double energy_pj(DramClass c) const;
  /// Standby energy up to `now`: per channel active_standby_mw over the time a row was open plus
  /// precharge_standby_mw over the time all banks were precharged.
  double background_energy_pj(Tick now) const;
  /// Refreshes so far x refresh_nj.
  double refresh_energy_pj() const;
  /// Whether the channels refresh (t_refi_ns and t_rfc_ns both positive).
  bool refresh_enabled() const { return timing_.t_refi_cycles > 0 && timing_.t_rfc_cycles > 0; }
  /// Sets the derived statistics (energy, rates, averages up to now()).
  void update_derived_stats();
  /// Its statistics now, derived ones updated first: the whole DRAM, each channel, each class.
  DramSnapshot snapshot();

  // Unit (run-loop watchdog)
  std::string_view name() const override { return name_; }
  bool has_pending_work() const override { return in_flight_ != 0; }
  std::uint64_t progress() const override { return stats_.completed.value(); }
  std::string stall_reason() const override;

 private:
  // A queued request; trivially copyable (its callback waits in done_[slot]) so the queues move
  // entries with memmove.
  struct Entry {
    std::uint32_t slot = 0;  // done_ slot holding on_complete
    Tick enqueued{0};
    Tick arrival{0};  // eligible for scheduling from this tick
    std::uint64_t row = 0;
    std::uint32_t bank = 0;
    std::uint32_t bytes = 0;  // whole bursts
    std::uint32_t lines = 1;  // line transfers merged (statistics)
    std::uint32_t column = 0; // byte offset in the row (the observer's column commands)
    std::uint64_t tag = 0;    // report_when_scheduled: the requester's tag
    DramClass cls = DramClass::Other;
    bool is_write = false;
    bool report = false;      // report_when_scheduled
    RowOutcome outcome = RowOutcome::Hit;  // Empty/Conflict once a row was opened for this request
  };
  struct Bank {
    std::int64_t open_row = -1;  // -1: precharged
    std::int64_t act_ready = 0;  // earliest activate (cycle)
    std::int64_t col_ready = 0;  // earliest column command (cycle)
    std::int64_t pre_ready = 0;  // earliest precharge (cycle)
  };
  struct Channel {
    std::vector<Entry> readq;
    std::vector<Entry> writeq;
    std::size_t read_lines = 0;   // lines queued (capacity, watermarks and occupancy count lines)
    std::size_t write_lines = 0;
    std::vector<Bank> banks;
    Tick bus_free{0};
    bool draining = false;
    std::uint32_t oldest_bypassed = 0;
    EventId wakeup;
    Tick wakeup_at{0};
    Tick occupancy_since{0};
    std::uint64_t read_occupancy_ps = 0;   // integral of read queue size over time
    std::uint64_t write_occupancy_ps = 0;  // integral of write queue size over time
    // tRRD / tFAW: the cycles of the last four activates (a ring; activates are issued in the
    // order the scheduler decides them).
    std::array<std::int64_t, 4> act_history{};
    std::uint64_t act_issued = 0;
    std::int8_t bus_dir = -1;          // direction of the last data on the bus: -1 none, 0 read, 1 write
    Tick last_burst_start{INT64_MIN / 2};  // start of the channel's last data burst (tCCD_S)
    std::vector<Tick> group_burst_start;  // per bank group, start of its last burst (tCCD_L)
    std::int64_t next_refresh = 0;     // cycle the next refresh falls due
    std::int64_t closed_since = 0;     // cycle since which every bank is precharged; -1: a row is open
    std::uint64_t precharged_ps = 0;   // precharge standby time before closed_since
    bool idle = true;                  // no request queued or in service since idle_from
    Tick idle_from{0};
    std::uint64_t pd_active_ps = 0;    // power-down time with a row open (ended periods)
    std::uint64_t pd_precharged_ps = 0;  // power-down time with every bank precharged (ended periods)
    DramChannelStats stats;
    /// When the data bus transferred (ps; bursts that touch are one interval), for the timeline.
    BusyIntervals bus_busy{kFrameBusyIntervals, 0.0};
  };

  RowOutcome outcome(const Bank& b, std::uint64_t row) const {
    return b.open_row == static_cast<std::int64_t>(row) ? RowOutcome::Hit
           : b.open_row < 0                           ? RowOutcome::Empty
                                                      : RowOutcome::Conflict;
  }
  // Statistics of a row opened (activate, and precharge for a conflict) for a request of `cls`.
  void account_activate(Channel& ch, RowOutcome o, DramClass cls);
  // Statistics of a request served (bytes; a row hit or miss as recorded when its row was opened).
  void account_request(Channel& ch, RowOutcome o, bool is_write, DramClass cls, std::uint32_t bytes,
                       std::uint32_t lines);
  void note_occupancy(Channel& ch, Tick now);
  // Performs every refresh of `ch` due at or before cycle n: it starts when due, or once every open
  // bank can be precharged (tRP after pre_ready), closes every bank and blocks activates for tRFC.
  void refresh_until(Channel& ch, std::int64_t n);
  // Splits the power-down period [from, to) of an idle channel into time with a row open and time
  // all precharged (refreshes close the rows: the split is at closed_since).
  void powerdown_split(const Channel& ch, Tick from, Tick to, std::uint64_t& active, std::uint64_t& precharged) const;
  // A request reaches an idle channel at `now`: books the power-down period it ends and delays
  // the channel's first command to tXP after the request's arrival.
  void wake(Channel& ch, Tick now);
  // Notes that a row opens at cycle a: ends the channel's precharge standby period.
  void note_row_open(Channel& ch, std::int64_t a);
  void kick(std::uint32_t c, Tick at);
  void wakeup(std::uint32_t c);
  // The queue the scheduler serves at `now`: writes from the high watermark down to the low one
  // (`draining` is the hysteresis state, updated) or when no read has arrived; else reads.
  std::vector<Entry>* active_queue(Channel& ch, Tick now, bool& draining) const;
  // Opens the row of `e` at cycle n (precharge if another row is open, then activate).
  void open_row(Channel& ch, Entry& e, std::int64_t n);
  // First cycle after n at which an arrived row hit of `q` could take its column command, given
  // `hit_banks`, the banks that hold one (wakeup knows them from its own pass over the queue).
  std::int64_t next_column_cycle(const Channel& ch, const std::vector<Entry>& q, std::uint64_t hit_banks, std::int64_t n,
                                 Tick now) const;
  // The banks holding an arrived row hit of `q` now, by a pass over it (set_verify_scheduler).
  std::uint64_t arrived_hit_banks(const Channel& ch, const std::vector<Entry>& q, Tick now) const;
  // First cycle at which the data of a column command issued then would start no more than one
  // DRAM cycle before the channel's data bus frees.
  // With a direction switch: a read command waits tWTR after the last write data; write data
  // starts tRTW after the last read data.
  std::int64_t bus_ready_cycle(const Channel& ch, std::int64_t n, Tick now, bool is_write) const {
    if (ch.bus_dir == 1 && !is_write) return cycle_ceil(ch.bus_free) + timing_.t_wtr_cycles;
    if (ch.bus_dir == 0 && is_write) return cycle_ceil(ch.bus_free + timing_.t_rtw) - timing_.t_cl_cycles;
    return (ch.bus_free > now ? clock_.cycles_at(ch.bus_free).count() : n) - timing_.t_cl_cycles;
  }
  // Earliest data start of a request to `bank` as tCCD_L (its group's last burst) and tCCD_S (the
  // channel's last burst) allow; Tick{0} without bank-group timing.
  Tick ccd_ready(const Channel& ch, std::uint32_t bank) const {
    Tick t{0};
    if (timing_.t_ccd_l.ps() > 0) t = std::max(t, ch.group_burst_start[bank % timing_.bank_groups] + timing_.t_ccd_l);
    if (timing_.t_ccd_s.ps() > 0) t = std::max(t, ch.last_burst_start + timing_.t_ccd_s);
    return t;
  }
  // The first command cycle whose data (RL later) would start no more than one cycle before
  // ccd_ready() (as for the data bus: commit() starts the data exactly then).
  std::int64_t ccd_ready_cycle(const Channel& ch, std::uint32_t bank) const {
    const Tick t = ccd_ready(ch, bank);
    return t.ps() <= 0 ? INT64_MIN / 2 : clock_.cycles_at(t).count() - timing_.t_cl_cycles;
  }
  void commit(std::uint32_t c, std::vector<Entry>& q, std::size_t i, std::int64_t n);
  void complete(std::uint32_t slot);
  std::int64_t ns_to_cycles(double ns) const;
  std::int64_t cycle_ceil(Tick t) const { return clock_.edge_index(t).count(); }

  std::string name_;
  EventQueue& eq_;
  EnergyParams energy_;
  double active_standby_mw_ = 0;
  double precharge_standby_mw_ = 0;
  double refresh_nj_ = 0;
  double active_powerdown_mw_ = 0;
  double precharge_powerdown_mw_ = 0;
  Tick powerdown_after_{0};  // 0: never
  Tick t_xp_{0};
  ClockDomain clock_;
  DramTiming timing_;
  DramMapping mapping_;
  std::uint64_t row_bytes_;
  std::uint32_t burst_bytes_;
  std::uint32_t banks_;
  std::size_t read_cap_;
  std::size_t write_cap_;
  std::size_t write_high_;  // write drains start at this many queued lines (dram.write_high_watermark)
  std::size_t write_low_;   // and end at this many (dram.write_low_watermark)
  // Fast mapping when row size, channels and banks are powers of two.
  bool pow2_map_ = false;
  unsigned row_shift_ = 0, ch_shift_ = 0, bank_shift_ = 0;

  std::vector<Channel> channels_;
  SlotPool<EventCallback> done_;           // on_complete of accepted requests, by slot
  std::uint64_t in_flight_ = 0;
  bool any_timed_ = false;
  Tick first_enqueue_{0};
  Tick last_completion_{0};
  std::uint64_t timed_bytes_ = 0;
  std::uint64_t timed_reads_ = 0;
  bool verify_scheduler_ = false;  // set_verify_scheduler
  std::function<void(std::uint32_t)> space_cb_;
  std::function<void(std::uint64_t, const DramSchedule&)> schedule_cb_;
  DramObserver* observer_ = nullptr;  // set_observer
  std::vector<int> first_need_;  // scratch of wakeup(): per bank, the oldest request needing a row

  DramStats stats_;
  std::array<DramClassStats, kDramClassCount> class_stats_;
};

}  // namespace tbdr
