#include "models/dram.hpp"
#include "models/dram_observer.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>
#include <type_traits>

#include "kernel/bits.hpp"

namespace tbdr {

namespace {

constexpr std::int64_t kNever = INT64_MAX;  // "no cycle": nothing to schedule

}  // namespace

Tick DramTiming::transfer(std::uint32_t bursts) const {
  return Tick{std::max<std::int64_t>(1, std::llround(static_cast<double>(bursts) * burst_ps))};
}

double dram_energy_pj(const EnergyParams& e, std::uint64_t read_bytes, std::uint64_t write_bytes,
                      std::uint64_t activates) {
  const double read_bits = 8.0 * static_cast<double>(read_bytes);
  const double write_bits = 8.0 * static_cast<double>(write_bytes);
  return read_bits * e.dram_read_pj_per_bit + write_bits * e.dram_write_pj_per_bit +
         (read_bits + write_bits) * e.dram_io_pj_per_bit +
         static_cast<double>(activates) * (e.dram_activate_precharge_nj * 1000.0);
}

Dram::Dram(const DramParams& p, const EnergyParams& e, EventQueue& eq, std::string scope)
    : name_(scope),
      eq_(eq),
      energy_(e),
      active_standby_mw_(p.active_standby_mw),
      precharge_standby_mw_(p.precharge_standby_mw),
      refresh_nj_(p.refresh_nj),
      active_powerdown_mw_(p.active_powerdown_mw),
      precharge_powerdown_mw_(p.precharge_powerdown_mw),
      powerdown_after_(Tick{std::llround(p.powerdown_after_ns * 1000.0)}),
      t_xp_(Tick{std::llround(p.t_xp_ns * 1000.0)}),
      clock_(ClockDomain::from_mhz("dram", p.clock_mhz)) {
  const auto bad = [&](const std::string& why) { throw std::invalid_argument("dram '" + scope + "': " + why); };
  if (p.channels < 1 || p.channels > 1024) bad("channels must be in [1, 1024]");
  if (p.banks < 1 || p.banks > kMaxBanks) bad("banks must be in [1, " + std::to_string(kMaxBanks) + "]");
  if (p.burst_bytes < 1 || p.row_bytes < p.burst_bytes || p.row_bytes % p.burst_bytes != 0) {
    bad("row_bytes must be a positive multiple of burst_bytes");
  }
  if (!(p.clock_mhz > 0) || !(p.transfers_per_clock > 0) || p.bus_width_bits < 1) {
    bad("clock_mhz, transfers_per_clock and bus_width_bits must be positive");
  }
  if ((p.burst_bytes * 8) % p.bus_width_bits != 0) {
    bad("burst_bytes (" + std::to_string(p.burst_bytes) + ") must be a whole number of transfers of bus_width_bits (" +
        std::to_string(p.bus_width_bits) + ")");
  }
  if (p.read_queue_entries < 1 || p.write_queue_entries < 1) bad("queues need at least one entry");
  const auto fraction = [](double v) { return v >= 0 && v <= 1; };
  if (!fraction(p.write_low_watermark) || !fraction(p.write_high_watermark)) bad("write watermarks must be in [0, 1]");
  mapping_ = p.address_mapping;
  row_bytes_ = static_cast<std::uint64_t>(p.row_bytes);
  burst_bytes_ = static_cast<std::uint32_t>(p.burst_bytes);
  banks_ = static_cast<std::uint32_t>(p.banks);
  read_cap_ = static_cast<std::size_t>(p.read_queue_entries);
  write_cap_ = static_cast<std::size_t>(p.write_queue_entries);
  write_high_ = std::max<std::size_t>(1, static_cast<std::size_t>(std::ceil(static_cast<double>(write_cap_) * p.write_high_watermark)));
  write_low_ = std::min(write_high_ - 1, static_cast<std::size_t>(static_cast<double>(write_cap_) * p.write_low_watermark));

  timing_.t_rcd_cycles = ns_to_cycles(p.t_rcd_ns);
  timing_.t_rp_cycles = ns_to_cycles(p.t_rp_ns);
  timing_.t_cl_cycles = ns_to_cycles(p.t_cl_ns);
  timing_.t_ras_cycles = ns_to_cycles(p.t_ras_ns);
  timing_.t_wr_cycles = ns_to_cycles(p.t_wr_ns);
  timing_.t_rrd_cycles = ns_to_cycles(p.t_rrd_ns);
  timing_.t_faw_cycles = ns_to_cycles(p.t_faw_ns);
  timing_.t_wtr_cycles = ns_to_cycles(p.t_wtr_ns);
  timing_.t_rtw = Tick{std::llround(p.t_rtw_ns * 1000.0)};
  if (p.bank_groups < 1 || p.banks % p.bank_groups != 0) bad("bank_groups must divide banks");
  timing_.bank_groups = static_cast<std::uint32_t>(p.bank_groups);
  timing_.t_ccd_l = Tick{std::llround(p.t_ccd_l_ns * 1000.0)};
  timing_.t_ccd_s = Tick{std::llround(p.t_ccd_s_ns * 1000.0)};
  if (p.t_refi_ns > 0 && p.t_rfc_ns > 0) {
    if (p.t_rfc_ns >= p.t_refi_ns) bad("t_rfc_ns must be shorter than t_refi_ns");
    timing_.t_refi_cycles = ns_to_cycles(p.t_refi_ns);
    timing_.t_rfc_cycles = ns_to_cycles(p.t_rfc_ns);
  }
  timing_.controller = Tick{std::llround(p.controller_latency_ns * 1000.0)};
  // bytes / (GB/s) = ns; one channel carries clock_mhz x transfers_per_clock x bus_width_bits / 8 MB/s
  // (DramParams::channel_peak_bandwidth_gbps), so a burst is burst_bytes x 8 / bus_width_bits transfers
  // at clock_mhz x transfers_per_clock per microsecond.
  timing_.burst_ps = static_cast<double>(burst_bytes_) * 1000.0 / p.channel_peak_bandwidth_gbps();
  stats_.peak_bandwidth_gbps.set(p.peak_bandwidth_gbps());

  pow2_map_ = is_pow2(row_bytes_) && is_pow2(static_cast<std::uint64_t>(p.channels)) && is_pow2(banks_);
  if (pow2_map_) {
    row_shift_ = log2_exact(row_bytes_);
    ch_shift_ = log2_exact(static_cast<std::uint64_t>(p.channels));
    bank_shift_ = log2_exact(banks_);
  }

  channels_.resize(static_cast<std::size_t>(p.channels));
  for (std::size_t c = 0; c < channels_.size(); ++c) {
    Channel& ch = channels_[c];
    ch.readq.reserve(read_cap_);
    ch.writeq.reserve(write_cap_);
    ch.banks.resize(banks_);
    ch.group_burst_start.assign(timing_.bank_groups, Tick{INT64_MIN / 2});
    ch.act_history.fill(std::numeric_limits<std::int64_t>::min() / 2);
    // Channels refresh staggered over the interval (channel c first at (c + 1) / channels of it),
    // as controllers do to keep the refreshes of different channels apart.
    ch.next_refresh = timing_.t_refi_cycles * static_cast<std::int64_t>(c + 1) / static_cast<std::int64_t>(channels_.size());
  }
  first_need_.assign(banks_, -1);
}

std::int64_t Dram::ns_to_cycles(double ns) const {
  // ceil(ns * f), with a tolerance so that 18 ns at 1 GHz is 18 cycles, not 19.
  const double cycles = ns * static_cast<double>(clock_.frequency_hz()) * 1e-9;
  return std::max<std::int64_t>(0, static_cast<std::int64_t>(std::ceil(cycles - 1e-6)));
}

DramCoord Dram::map(std::uint64_t addr) const {
  DramCoord d;
  const auto nch = static_cast<std::uint64_t>(channels_.size());
  std::uint64_t x;
  if (pow2_map_) {
    d.column = static_cast<std::uint32_t>(addr & (row_bytes_ - 1));
    x = addr >> row_shift_;
    if (mapping_ == DramMapping::RowBankChannelColumn) {
      d.channel = static_cast<std::uint32_t>(x & (nch - 1));
      x >>= ch_shift_;
      d.bank = static_cast<std::uint32_t>(x & (banks_ - 1));
      d.row = x >> bank_shift_;
    } else {
      d.bank = static_cast<std::uint32_t>(x & (banks_ - 1));
      x >>= bank_shift_;
      d.channel = static_cast<std::uint32_t>(x & (nch - 1));
      d.row = x >> ch_shift_;
    }
    return d;
  }
  d.column = static_cast<std::uint32_t>(addr % row_bytes_);
  x = addr / row_bytes_;
  if (mapping_ == DramMapping::RowBankChannelColumn) {
    d.channel = static_cast<std::uint32_t>(x % nch);
    x /= nch;
    d.bank = static_cast<std::uint32_t>(x % banks_);
    d.row = x / banks_;
  } else {
    d.bank = static_cast<std::uint32_t>(x % banks_);
    x /= banks_;
    d.channel = static_cast<std::uint32_t>(x % nch);
    d.row = x / nch;
  }
  return d;
}

void Dram::account_activate(Channel& ch, RowOutcome o, DramClass cls) {
  ++stats_.activates;
  ++ch.stats.activates;
  ++class_stats_[static_cast<std::size_t>(cls)].activates;
  if (o == RowOutcome::Conflict) {
    ++stats_.precharges;
    ++ch.stats.precharges;
  }
}

void Dram::account_request(Channel& ch, RowOutcome o, bool is_write, DramClass cls, std::uint32_t bytes,
                           std::uint32_t lines) {
  DramClassStats& cs = class_stats_[static_cast<std::size_t>(cls)];
  DramChannelStats& chs = ch.stats;
  ++stats_.queue_entries_served;
  if (is_write) {
    stats_.writes += lines;
    stats_.write_bytes += bytes;
    cs.writes += lines;
    cs.write_bytes += bytes;
    chs.writes += lines;
  } else {
    stats_.reads += lines;
    stats_.read_bytes += bytes;
    cs.reads += lines;
    cs.read_bytes += bytes;
    chs.reads += lines;
  }
  chs.bytes += bytes;
  // The first line found the row as `o`; the rest of a chain follow it in the open row.
  const std::uint32_t hits = o == RowOutcome::Hit ? lines : lines - 1;
  stats_.row_hits += hits;
  chs.row_hits += hits;
  if (o == RowOutcome::Hit) return;
  ++stats_.row_misses;
  ++chs.row_misses;
  if (o == RowOutcome::Empty) {
    ++stats_.row_misses_empty;
  } else {
    ++stats_.row_conflicts;
  }
}

RowOutcome Dram::access_functional(std::uint64_t addr, std::uint32_t bytes, bool is_write, DramClass cls,
                                   std::uint32_t lines) {
  const DramCoord d = map(addr);
  Channel& ch = channels_[d.channel];
  Bank& b = ch.banks[d.bank];
  const RowOutcome o = outcome(b, d.row);
  if (o != RowOutcome::Hit) {
    b.open_row = static_cast<std::int64_t>(d.row);
    ch.closed_since = -1;  // no time on this path: the background counts it as active standby
    account_activate(ch, o, cls);
  }
  account_request(ch, o, is_write, cls, transfer_bytes(bytes), std::max<std::uint32_t>(1, lines));
  return o;
}

bool Dram::can_accept(std::uint64_t addr, bool is_write) const {
  const Channel& ch = channels_[map(addr).channel];
  return is_write ? ch.write_lines < write_cap_ : ch.read_lines < read_cap_;
}

bool Dram::enqueue(DramRequest&& req) {
  static_assert(std::is_trivially_copyable_v<Entry>, "the queues move entries with memmove");
  if (req.bytes == 0) throw std::invalid_argument("dram: request of 0 bytes");
  const DramCoord d = map(req.addr);
  if (d.column + static_cast<std::uint64_t>(req.bytes) > row_bytes_) {
    throw std::invalid_argument("dram: request of " + std::to_string(req.bytes) + " bytes at " +
                                std::to_string(req.addr) + " crosses a row boundary");
  }
  Channel& ch = channels_[d.channel];
  std::vector<Entry>& q = req.is_write ? ch.writeq : ch.readq;
  const std::size_t cap = req.is_write ? write_cap_ : read_cap_;
  const std::uint32_t lines = std::max<std::uint32_t>(1, req.lines);
  if (lines > cap) {
    throw std::invalid_argument("dram: request of " + std::to_string(lines) + " lines exceeds the " +
                                std::to_string(cap) + "-entry queue");
  }
  std::size_t& queued = req.is_write ? ch.write_lines : ch.read_lines;
  if (queued + lines > cap) {
    ++stats_.queue_full_rejections;
    if (req.is_write) {
      ++ch.stats.write_queue_full;
    } else {
      ++ch.stats.read_queue_full;
    }
    return false;
  }
  const Tick now = eq_.now();
  note_occupancy(ch, now);
  if (ch.idle) wake(ch, now);
  Entry e;
  e.report = req.report_when_scheduled;
  e.tag = req.tag;
  if (e.report) {
    if (!schedule_cb_) throw std::logic_error("dram: report_when_scheduled without a schedule callback");
  } else {
    e.slot = done_.acquire();
    done_[e.slot] = std::move(req.on_complete);
  }
  e.enqueued = now;
  e.arrival = now + timing_.controller;
  e.row = d.row;
  e.bank = d.bank;
  e.bytes = transfer_bytes(req.bytes);
  e.lines = lines;
  e.column = d.column;
  e.cls = req.cls;
  e.is_write = req.is_write;
  q.push_back(e);
  queued += lines;
  if (!any_timed_) {
    any_timed_ = true;
    first_enqueue_ = now;
  }
  ++in_flight_;
  if (observer_) observer_->request(now, req.addr, e.bytes, e.is_write);
  kick(d.channel, e.arrival);
  return true;
}

void Dram::note_occupancy(Channel& ch, Tick now) {
  const auto dt = static_cast<std::uint64_t>((now - ch.occupancy_since).ps());
  ch.read_occupancy_ps += ch.read_lines * dt;
  ch.write_occupancy_ps += ch.write_lines * dt;
  ch.occupancy_since = now;
}

void Dram::refresh_until(Channel& ch, std::int64_t n) {
  if (!refresh_enabled()) return;
  while (ch.next_refresh <= n) {
    // All-bank refresh: every open bank is precharged first (when it allows, then tRP), a closed
    // bank must have finished its precharge (act_ready); the banks stay closed for tRFC.
    std::int64_t start = ch.next_refresh;
    for (const Bank& b : ch.banks) start = std::max(start, b.open_row >= 0 ? b.pre_ready + timing_.t_rp_cycles : b.act_ready);
    const std::int64_t end = start + timing_.t_rfc_cycles;
    for (Bank& b : ch.banks) {
      b.open_row = -1;
      b.act_ready = end;
      b.col_ready = end;
      b.pre_ready = end;
    }
    if (ch.closed_since < 0) ch.closed_since = end;
    ++stats_.refreshes;
    ++ch.stats.refreshes;
    if (observer_) observer_->refresh(static_cast<std::uint32_t>(&ch - channels_.data()), start, 1, timing_.t_refi_cycles);
    const bool on_time = start == ch.next_refresh;
    ch.next_refresh += timing_.t_refi_cycles;
    if (on_time && ch.next_refresh <= n) {
      // Every bank is now closed and free from `end`, before the next refresh is due (tRFC <
      // tREFI): each further refresh up to n starts when due and ends tRFC later, as this one did.
      // Book them at once: an idle channel catches up thousands of refreshes per frame.
      const std::int64_t more = (n - ch.next_refresh) / timing_.t_refi_cycles + 1;
      const std::int64_t last_end = ch.next_refresh + (more - 1) * timing_.t_refi_cycles + timing_.t_rfc_cycles;
      for (Bank& b : ch.banks) {
        b.act_ready = last_end;
        b.col_ready = last_end;
        b.pre_ready = last_end;
      }
      if (observer_) observer_->refresh(static_cast<std::uint32_t>(&ch - channels_.data()), ch.next_refresh, more, timing_.t_refi_cycles);
      stats_.refreshes += static_cast<std::uint64_t>(more);
      ch.stats.refreshes += static_cast<std::uint64_t>(more);
      ch.next_refresh += more * timing_.t_refi_cycles;
      return;
    }
  }
}

void Dram::powerdown_split(const Channel& ch, Tick from, Tick to, std::uint64_t& active, std::uint64_t& precharged) const {
  if (to <= from) return;
  Tick closed = to;  // from here on every bank is precharged
  if (ch.closed_since >= 0) closed = std::clamp(clock_.tick_of(Cycles{ch.closed_since}), from, to);
  active += static_cast<std::uint64_t>((closed - from).ps());
  precharged += static_cast<std::uint64_t>((to - closed).ps());
}

void Dram::wake(Channel& ch, Tick now) {
  ch.idle = false;
  if (powerdown_after_.ps() <= 0 || now <= ch.idle_from + powerdown_after_) return;
  refresh_until(ch, clock_.cycles_at(now).count());  // the refreshes of the idle period, for the split
  powerdown_split(ch, ch.idle_from + powerdown_after_, now, ch.pd_active_ps, ch.pd_precharged_ps);
  ++stats_.powerdown_exits;
  // Power-down exit: no command before tXP after the request reaches the controller.
  const std::int64_t ready = cycle_ceil(now + timing_.controller + t_xp_);
  for (Bank& b : ch.banks) {
    b.act_ready = std::max(b.act_ready, ready);
    b.col_ready = std::max(b.col_ready, ready);
    b.pre_ready = std::max(b.pre_ready, ready);
  }
}

void Dram::note_row_open(Channel& ch, std::int64_t a) {
  if (ch.closed_since < 0) return;
  const Tick from = clock_.tick_of(Cycles{ch.closed_since}), to = clock_.tick_of(Cycles{a});
  if (to > from) ch.precharged_ps += static_cast<std::uint64_t>((to - from).ps());
  ch.closed_since = -1;
}

void Dram::kick(std::uint32_t c, Tick at) {
  Channel& ch = channels_[c];
  const Tick edge = clock_.next_edge(std::max(at, eq_.now()));
  if (eq_.is_pending(ch.wakeup)) {
    if (ch.wakeup_at <= edge) return;
    eq_.cancel(ch.wakeup);
  }
  ch.wakeup_at = edge;
  ch.wakeup = eq_.schedule(edge, Priority::UnitOperate, [this, c] { wakeup(c); });
}

void Dram::open_row(Channel& ch, Entry& e, std::int64_t n) {
  Bank& b = ch.banks[e.bank];
  const RowOutcome o = b.open_row < 0 ? RowOutcome::Empty : RowOutcome::Conflict;
  // Precharge when the bank allows it (tRAS after its activate, the last data out, tWR after the
  // last write), activate tRP later; the column command may follow tRCD after the activate.
  const std::int64_t t_bank =
      o == RowOutcome::Empty ? std::max(n, b.act_ready) : std::max(n, b.pre_ready) + timing_.t_rp_cycles;
  // tRRD after the channel's previous activate, tFAW after the fourth-last one.
  const std::int64_t t_act = std::max({t_bank, ch.act_history[(ch.act_issued + 3) % 4] + timing_.t_rrd_cycles,
                                       ch.act_history[ch.act_issued % 4] + timing_.t_faw_cycles});
  if (t_act > t_bank) ++stats_.activates_delayed_rrd_faw;
  ch.act_history[ch.act_issued % 4] = t_act;
  ++ch.act_issued;
  note_row_open(ch, t_act);
  b.open_row = static_cast<std::int64_t>(e.row);
  b.act_ready = t_act;
  b.col_ready = t_act + timing_.t_rcd_cycles;
  b.pre_ready = t_act + timing_.t_ras_cycles;
  e.outcome = o;
  account_activate(ch, o, e.cls);
  if (observer_) observer_->activate(static_cast<std::uint32_t>(&ch - channels_.data()), e.bank, e.row, o == RowOutcome::Conflict ? t_bank - timing_.t_rp_cycles : -1, t_act);
}

std::int64_t Dram::next_column_cycle(const Channel& ch, const std::vector<Entry>& q, std::uint64_t hit_banks, std::int64_t n,
                                     Tick now) const {
  if (q.empty()) return kNever;
  const std::int64_t bus_ready = bus_ready_cycle(ch, n, now, q.front().is_write);
  // When a row hit can go depends only on its bank: the earliest of the banks holding one.
  std::int64_t next = kNever;
  for (; hit_banks != 0; hit_banks &= hit_banks - 1) {
    const auto bank = static_cast<std::uint32_t>(__builtin_ctzll(hit_banks));
    next = std::min(next, std::max({ch.banks[bank].col_ready, bus_ready, ccd_ready_cycle(ch, bank)}));
  }
  return next == kNever ? kNever : std::max(next, n + 1);
}

std::uint64_t Dram::arrived_hit_banks(const Channel& ch, const std::vector<Entry>& q, Tick now) const {
  std::uint64_t banks = 0;
  for (const Entry& e : q) {
    if (e.arrival > now) break;
    if (ch.banks[e.bank].open_row == static_cast<std::int64_t>(e.row)) banks |= std::uint64_t{1} << e.bank;
  }
  return banks;
}

void Dram::commit(std::uint32_t c, std::vector<Entry>& q, std::size_t i, std::int64_t n) {
  Channel& ch = channels_[c];
  const Tick now = eq_.now();
  note_occupancy(ch, now);
  const Entry e = q[i];
  q.erase(q.begin() + static_cast<std::ptrdiff_t>(i));
  (e.is_write ? ch.write_lines : ch.read_lines) -= e.lines;

  Bank& b = ch.banks[e.bank];
  b.col_ready = n + 1;
  const Tick data_natural = clock_.tick_of(Cycles{n + timing_.t_cl_cycles});
  const bool r_to_w = ch.bus_dir == 0 && e.is_write;
  const Tick bus_start = std::max(data_natural, r_to_w ? ch.bus_free + timing_.t_rtw : ch.bus_free);
  if (r_to_w) ++stats_.read_to_write_turnarounds;
  if (ch.bus_dir == 1 && !e.is_write) ++stats_.write_to_read_turnarounds;
  ch.bus_dir = e.is_write ? 1 : 0;
  const std::uint32_t bursts = e.bytes / burst_bytes_;
  const Tick busy = timing_.transfer(bursts);
  Tick start = bus_start, duration = busy;
  if (timing_.t_ccd_l.ps() > 0 || timing_.t_ccd_s.ps() > 0) {
    // Bank-group timing: the first burst waits for tCCD_L after its group's last burst and tCCD_S
    // after the channel's; the entry's own bursts (one bank, so one group) follow each other
    // max(burst, tCCD_L, tCCD_S) apart.
    const Tick ccd = ccd_ready(ch, e.bank);
    start = std::max(bus_start, ccd);
    // The scheduler waited for tCCD (so the data bus itself was free earlier).
    if (ccd > (r_to_w ? ch.bus_free + timing_.t_rtw : ch.bus_free)) ++stats_.bursts_delayed_ccd;
    const std::int64_t spacing =
        std::max({timing_.transfer(1).ps(), timing_.t_ccd_l.ps(), timing_.t_ccd_s.ps()});
    const Tick last_burst = start + Tick{spacing * static_cast<std::int64_t>(bursts - 1)};
    duration = (last_burst - start) + timing_.transfer(1);
    ch.group_burst_start[e.bank % timing_.bank_groups] = last_burst;
    ch.last_burst_start = last_burst;
  }
  const Tick end = start + duration;
  ch.bus_free = end;
  const std::int64_t end_c = cycle_ceil(end);
  b.pre_ready = std::max(b.pre_ready, e.is_write ? end_c + timing_.t_wr_cycles : end_c);

  account_request(ch, e.outcome, e.is_write, e.cls, e.bytes, e.lines);
  if (observer_) observer_->column(c, e.bank, e.row, e.column, e.is_write, n, bursts, e.lines, e.enqueued, start, end, timing_.controller);
  if (ch.readq.empty() && ch.writeq.empty()) {  // nothing left: idle once this data is through
    ch.idle = true;
    ch.idle_from = end;
  }
  ch.stats.busy_ps += static_cast<std::uint64_t>(busy.ps());
  ch.bus_busy.add(static_cast<double>(start.ps()), static_cast<double>(end.ps()), static_cast<double>(busy.ps()));
  timed_bytes_ += e.bytes;
  const Tick done = end + timing_.controller;
  if (!e.is_write) {
    // Per line: line i of L is back controller latency after (i + 1) / L of the transfer.
    const auto L = static_cast<std::int64_t>(e.lines);
    const std::int64_t first_done = (start + timing_.controller - e.enqueued).ps();
    stats_.read_latency_total_ps += static_cast<std::uint64_t>(L * first_done + duration.ps() * (L + 1) / 2);
    timed_reads_ += e.lines;
  }
  if (e.report) {
    --in_flight_;
    ++stats_.completed;
    last_completion_ = std::max(last_completion_, done);
    schedule_cb_(e.tag, DramSchedule{start, end, timing_.controller});
    return;
  }
  const std::uint32_t slot = e.slot;
  eq_.schedule(done, Priority::DramResponse, [this, slot] { complete(slot); });
}

void Dram::complete(std::uint32_t slot) {
  EventCallback cb = std::move(done_[slot]);
  done_[slot].reset();
  done_.release(slot);
  --in_flight_;
  ++stats_.completed;
  last_completion_ = std::max(last_completion_, eq_.now());
  if (cb) cb();
}

std::vector<Dram::Entry>* Dram::active_queue(Channel& ch, Tick now, bool& draining) const {
  if (!draining && ch.write_lines >= write_high_) {
    draining = true;
  } else if (draining && ch.write_lines <= write_low_) {
    draining = false;
  }
  const bool reads_arrived = !ch.readq.empty() && ch.readq.front().arrival <= now;
  const bool writes_arrived = !ch.writeq.empty() && ch.writeq.front().arrival <= now;
  if (writes_arrived && (draining || !reads_arrived)) return &ch.writeq;
  if (reads_arrived) return &ch.readq;
  return nullptr;
}

void Dram::wakeup(std::uint32_t c) {
  Channel& ch = channels_[c];
  const Tick now = eq_.now();
  const std::int64_t n = clock_.cycles_at(now).count();
  refresh_until(ch, n);
  const bool was_draining = ch.draining;
  std::vector<Entry>* q = active_queue(ch, now, ch.draining);
  if (ch.draining && !was_draining) ++ch.stats.write_drains;

  std::int64_t next = kNever;
  bool freed = false;
  if (q != nullptr) {
    // One pass over the arrived requests: the banks whose open row is still wanted (row hits come
    // first), the oldest request needing a row per bank, and the oldest row hit whose column
    // command can issue now (its bank allows it and its data would not start more than one cycle
    // before the data bus frees).
    const std::int64_t bus_ready = bus_ready_cycle(ch, n, now, q->front().is_write);
    std::uint64_t wanted = 0;
    std::uint64_t wanted_twice = 0;  // banks with more than one arrived row hit
    std::fill(first_need_.begin(), first_need_.end(), -1);
    int issue = -1;
    std::uint64_t not_ready = 0;  // banks whose row hits cannot take their column command now
    for (std::size_t i = 0; i < q->size(); ++i) {
      const Entry& e = (*q)[i];
      if (e.arrival > now) break;
      const Bank& b = ch.banks[e.bank];
      if (b.open_row == static_cast<std::int64_t>(e.row)) {
        const std::uint64_t bit = std::uint64_t{1} << e.bank;
        wanted_twice |= wanted & bit;
        wanted |= bit;
        if (issue < 0 && (not_ready & bit) == 0) {
          if (std::max({b.col_ready, bus_ready, ccd_ready_cycle(ch, e.bank)}) <= n) {
            issue = static_cast<int>(i);
          } else {
            not_ready |= bit;  // the same for every row hit of this bank
          }
        }
      } else if (first_need_[e.bank] < 0) {
        first_need_[e.bank] = static_cast<int>(i);
      }
    }
    // Row preparation: the oldest request whose bank's open row nobody arrived still wants (the
    // oldest request overrides that after kStarvationCap younger ones were served before it).
    const bool starving = ch.oldest_bypassed >= kStarvationCap;
    int prep = -1, eligible = 0;
    // A starving oldest request may close a row this cycle's column command still reads: it waits a
    // cycle, so that the precharge follows that command's data (and the new row's tRCD holds).
    const std::int64_t issue_bank = issue >= 0 ? (*q)[static_cast<std::size_t>(issue)].bank : -1;
    for (std::uint32_t bank = 0; bank < banks_; ++bank) {
      const int i = first_need_[bank];
      if (i < 0 || (((wanted >> bank) & 1) != 0 && !(i == 0 && starving))) continue;
      ++eligible;
      if (bank == issue_bank) {
        ++eligible;  // come back next cycle for it
        continue;
      }
      if (prep < 0 || i < prep) prep = i;
    }
    const bool oldest_needs_row = first_need_[q->front().bank] == 0;
    // The banks holding an arrived row hit once this cycle's decisions are made (what a second
    // pass over the queue would find): the issued request's bank loses its hit if it was the
    // only one there, then the prepared request's bank gains one (the request itself; any other
    // hit it had was to the row now closed).
    std::uint64_t hits_after = wanted;
    if (issue >= 0) {
      const std::uint64_t bit = std::uint64_t{1} << (*q)[static_cast<std::size_t>(issue)].bank;
      if ((wanted_twice & bit) == 0) hits_after &= ~bit;
    }
    if (prep >= 0) {
      hits_after |= std::uint64_t{1} << (*q)[static_cast<std::size_t>(prep)].bank;
      open_row(ch, (*q)[static_cast<std::size_t>(prep)], n);
      if (prep == 0) ch.oldest_bypassed = 0;
    }
    if (issue >= 0) {
      if (issue == 0) {
        ch.oldest_bypassed = 0;
      } else if (oldest_needs_row && prep != 0) {
        ++ch.oldest_bypassed;
      }
      commit(c, *q, static_cast<std::size_t>(issue), n);
      freed = true;
    }
    // One row and one column decision per DRAM cycle: come back next cycle if another row can be
    // opened, else when the first row hit can take its column command.
    if (verify_scheduler_ && arrived_hit_banks(ch, *q, now) != hits_after) {
      throw std::logic_error("Dram::wakeup: the banks with a row hit after this cycle's decisions differ from a pass over the queue");
    }
    next = eligible > 1 ? n + 1 : next_column_cycle(ch, *q, hits_after, n, now);
    // The other queue's turn (this one emptied or a watermark was crossed): look again next cycle.
    bool draining = ch.draining;
    if (active_queue(ch, now, draining) != q) next = n + 1;
    if (next == kNever && !q->empty() && q->front().arrival <= now) next = n + 1;  // defensive
  }
  for (const std::vector<Entry>* qq : {&ch.readq, &ch.writeq}) {
    if (!qq->empty() && qq->front().arrival > now) next = std::min(next, cycle_ceil(qq->front().arrival));
  }
  if (next != kNever && (!ch.readq.empty() || !ch.writeq.empty())) {
    kick(c, clock_.tick_of(Cycles{std::max(next, n + 1)}));
  }
  if (freed && space_cb_) space_cb_(c);
}

DramTraffic Dram::traffic() const {
  DramTraffic t;
  for (std::size_t c = 0; c < kDramClassCount; ++c) {
    t.read_bytes[c] = class_stats_[c].read_bytes.value();
    t.write_bytes[c] = class_stats_[c].write_bytes.value();
  }
  return t;
}

double Dram::energy_pj() const {
  return dram_energy_pj(energy_, stats_.read_bytes.value(), stats_.write_bytes.value(), stats_.activates.value()) +
         background_energy_pj(eq_.now()) + refresh_energy_pj();
}

double Dram::background_energy_pj(Tick now) const {
  // mW x ps = 1e-3 W x 1e-12 s = 1e-15 J = 1e-3 pJ.
  double pj = 0;
  for (const Channel& ch : channels_) {
    std::uint64_t pre = ch.precharged_ps;
    if (ch.closed_since >= 0) {
      const Tick from = clock_.tick_of(Cycles{ch.closed_since});
      if (now > from) pre += static_cast<std::uint64_t>((now - from).ps());
    }
    const auto elapsed = static_cast<std::uint64_t>(std::max<std::int64_t>(0, now.ps()));
    pre = std::min(pre, elapsed);
    pj += (active_standby_mw_ * static_cast<double>(elapsed - pre) + precharge_standby_mw_ * static_cast<double>(pre)) * 1e-3;
    // Power-down replaces standby over its periods (the ended ones and an idle channel's current one).
    std::uint64_t pd_active = ch.pd_active_ps, pd_pre = ch.pd_precharged_ps;
    if (ch.idle && powerdown_after_.ps() > 0) powerdown_split(ch, ch.idle_from + powerdown_after_, now, pd_active, pd_pre);
    pj -= ((active_standby_mw_ - active_powerdown_mw_) * static_cast<double>(pd_active) +
           (precharge_standby_mw_ - precharge_powerdown_mw_) * static_cast<double>(pd_pre)) * 1e-3;
  }
  return pj;
}

double Dram::refresh_energy_pj() const { return static_cast<double>(stats_.refreshes.value()) * (refresh_nj_ * 1000.0); }

double Dram::energy_pj(DramClass c) const {
  const DramClassStats& cs = class_stats_[static_cast<std::size_t>(c)];
  return dram_energy_pj(energy_, cs.read_bytes.value(), cs.write_bytes.value(), cs.activates.value());
}

void Dram::update_derived_stats() {
  const Tick now = eq_.now();
  const double elapsed_ps = static_cast<double>(now.ps());
  for (Channel& ch : channels_) {
    refresh_until(ch, clock_.cycles_at(now).count());  // the refreshes an idle channel did meanwhile
    note_occupancy(ch, now);
    std::uint64_t pre = ch.precharged_ps;
    if (ch.closed_since >= 0 && now > clock_.tick_of(Cycles{ch.closed_since})) {
      pre += static_cast<std::uint64_t>((now - clock_.tick_of(Cycles{ch.closed_since})).ps());
    }
    ch.stats.precharged_ps.set(pre);
    std::uint64_t pd_active = ch.pd_active_ps, pd_pre = ch.pd_precharged_ps;
    if (ch.idle && powerdown_after_.ps() > 0) powerdown_split(ch, ch.idle_from + powerdown_after_, now, pd_active, pd_pre);
    ch.stats.powerdown_ps.set(pd_active + pd_pre);
    DramChannelStats& s = ch.stats;
    s.read_queue_occupancy_avg.set(elapsed_ps > 0 ? static_cast<double>(ch.read_occupancy_ps) / elapsed_ps : 0.0);
    s.write_queue_occupancy_avg.set(elapsed_ps > 0 ? static_cast<double>(ch.write_occupancy_ps) / elapsed_ps : 0.0);
    s.utilization.set(elapsed_ps > 0 ? static_cast<double>(s.busy_ps.value()) / elapsed_ps : 0.0);
  }
  const std::uint64_t requests = stats_.reads.value() + stats_.writes.value();
  stats_.row_hit_rate.set(requests == 0 ? 0.0 : static_cast<double>(stats_.row_hits.value()) / static_cast<double>(requests));
  stats_.avg_read_latency_ns.set(
      timed_reads_ == 0 ? 0.0 : static_cast<double>(stats_.read_latency_total_ps.value()) * 1e-3 / static_cast<double>(timed_reads_));
  const std::int64_t window_ps = (last_completion_ - first_enqueue_).ps();
  stats_.achieved_bandwidth_gbps.set(window_ps <= 0 ? 0.0 : static_cast<double>(timed_bytes_) * 1000.0 / static_cast<double>(window_ps));
  const double read_bits = 8.0 * static_cast<double>(stats_.read_bytes.value());
  const double write_bits = 8.0 * static_cast<double>(stats_.write_bytes.value());
  stats_.energy_read_pj.set(read_bits * energy_.dram_read_pj_per_bit);
  stats_.energy_write_pj.set(write_bits * energy_.dram_write_pj_per_bit);
  stats_.energy_io_pj.set((read_bits + write_bits) * energy_.dram_io_pj_per_bit);
  stats_.energy_activate_pj.set(static_cast<double>(stats_.activates.value()) * (energy_.dram_activate_precharge_nj * 1000.0));
  stats_.energy_background_pj.set(background_energy_pj(now));
  stats_.energy_refresh_pj.set(refresh_energy_pj());
  stats_.energy_dynamic_pj.set(
      dram_energy_pj(energy_, stats_.read_bytes.value(), stats_.write_bytes.value(), stats_.activates.value()));
  stats_.energy_pj.set(energy_pj());
  stats_.energy_per_bit_pj.set(read_bits + write_bits > 0 ? energy_pj() / (read_bits + write_bits) : 0.0);
  for (std::size_t c = 0; c < kDramClassCount; ++c) class_stats_[c].energy_pj.set(energy_pj(static_cast<DramClass>(c)));
}

DramSnapshot Dram::snapshot() {
  update_derived_stats();
  DramSnapshot s{name_, stats_, {}, class_stats_};
  for (const Channel& ch : channels_) s.channels.push_back(ch.stats);
  return s;
}

std::string Dram::stall_reason() const {
  std::string s = std::to_string(in_flight_) + " requests in flight;";
  for (std::size_t c = 0; c < channels_.size(); ++c) {
    const Channel& ch = channels_[c];
    s += " ch" + std::to_string(c) + ": " + std::to_string(ch.readq.size()) + " reads, " +
         std::to_string(ch.writeq.size()) + " writes queued" + (ch.draining ? " (draining writes)" : "") + ";";
  }
  return s;
}

}  // namespace tbdr
