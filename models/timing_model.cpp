#include "models/timing_model.hpp"

#include "models/dram_observer.hpp"

#include <algorithm>
#include <cmath>
#include <deque>
#include <functional>
#include <map>
#include <tuple>
#include <memory>
#include <stdexcept>

#include "models/dma_stream.hpp"
#include "models/frame_address_map.hpp"
#include "models/memory_system.hpp"
#include "models/task_slots.hpp"
#include "models/tile_records.hpp"
#include "models/work_feed.hpp"
#include "kernel/errors.hpp"
#include "kernel/event_queue.hpp"
#include "kernel/run_loop.hpp"
#include "kernel/time.hpp"

namespace tbdr {

namespace {

/// Lanes of a 2x2 quad: the unit fragment shading runs in (helpers included).
constexpr std::uint64_t kLanesPerQuad = 4;

/// A FIFO server with a throughput: jobs reserve it in arrival order.
struct Server {
  TimedUnit unit = TimedUnit::Binning;  ///< which unit it is (its index in TimingResult::units)
  Tick free_at{0};
  double busy_cycles = 0;
  /// Its busy spans and the spans its work waited (for memory, for a full queue downstream), in
  /// cycles, merged as they grow: the stalled time is the time it was waiting and not busy, counted
  /// once however many of its tiles wait at once (stalled_cycles()), so that busy + stalled + idle
  /// is the frame.
  std::vector<std::pair<double, double>> spans;
  std::size_t spans_merged = 0;  ///< size of `spans` after its last merge

  /// Notes a span it was busy or waited, [from, to) in cycles.
  void add_span(double from, double to) {
    if (to <= from) return;
    if (!spans.empty() && from <= spans.back().second && from >= spans.back().first) {
      spans.back().second = std::max(spans.back().second, to);  // (back-to-back reservations)
      return;
    }
    spans.emplace_back(from, to);
    if (spans.size() >= 2 * std::max<std::size_t>(spans_merged, kSpansBeforeMerge)) merge_spans();
  }
  /// Sorts and merges the spans (their union stays the same).
  void merge_spans() {
    std::sort(spans.begin(), spans.end());
    std::size_t n = 0;
    for (const auto& sp : spans) {
      if (n > 0 && sp.first <= spans[n - 1].second) {
        spans[n - 1].second = std::max(spans[n - 1].second, sp.second);
      } else {
        spans[n++] = sp;
      }
    }
    spans.resize(n);
    spans_merged = n;
  }
  /// Cycles it waited while not busy: the union of its spans less its busy cycles (the busy spans
  /// are disjoint: a reservation starts when the one before it ends).
  double stalled_cycles() {
    merge_spans();
    double covered = 0;
    for (const auto& sp : spans) covered += sp.second - sp.first;
    return std::max(0.0, covered - busy_cycles);
  }
  /// Spans kept before the first merge (later: twice the merged count); a merge sorts them, so
  /// about log2 of the frame's spans merges in all.
  static constexpr std::size_t kSpansBeforeMerge = 4096;
};

/// Scheduling state of one tile of the current render.
struct TileState {
  Tick fetch_start{0};
  bool fetched = false;
  int pending_streams = 0;
  int pending_shading = 0;  ///< USC work and texture fetch still to finish
  Tick usc_end{0};          ///< when its ALU and filtering work is done
  std::uint64_t slots = 0;  ///< task slots it holds while resident on the USCs
  const TileWork* work = nullptr;  ///< its work, once dispatched (from the feed)
};

/// The scheduler of the frame's work; a Unit so the run loop's watchdog can name it when stuck.
class TimingSim final : public Unit {
 public:
  TimingSim(const HwConfig& hw, WorkFeed& feed)
      : hw_(hw),
        feed_(feed),
        work_(feed.frame()),
        core_(ClockDomain::from_mhz("core", hw.gpu.core_clock_mhz)),
        mem_(hw, eq_, "mem"),
        map_(work_, static_cast<std::uint64_t>(hw.tiling.pb_capacity_bytes), mem_.address_space()),
        slots_(static_cast<std::uint64_t>(hw.usc.count * hw.usc.tasks_in_flight)) {
    for (std::size_t u = 0; u < kTimedUnitCount; ++u) servers_[u].unit = static_cast<TimedUnit>(u);
    tile_buffer_rate_ = static_cast<double>(hw.usc.count) * hw.pls.tile_buffer_bytes_per_clock;
    alu_rate_ = static_cast<double>(hw.usc.count * hw.usc.lanes) * hw.usc.alu_ops_per_lane_per_clock;
    tex_rate_ = static_cast<double>(hw.texture.units) * hw.texture.texels_per_clock;
    raster_rate_ = static_cast<double>(hw.isp.samples_per_clock * hw.isp.raster_pipes);
    texture_line_bytes_ = static_cast<std::uint64_t>(hw.cache.texture.line_bytes);
  }

  /// Reports the DRAM's requests and commands to `o` (models/dram_observer.hpp).
  void observe_dram(DramObserver* o) {
    o->attach(mem_.dram());
    mem_.dram().set_observer(o);
  }

  TimingResult run() {
    per_command_intervals_ = std::clamp(kFrameBusyIntervals / std::max<std::size_t>(1, feed_.expected_commands()),
                                        kMinCommandBusyIntervals, kMaxCommandBusyIntervals);
    eq_.schedule(Tick{0}, [this] {
      try_start_binning();
      try_start_fragment();
    });
    RunLoop loop(eq_, {&mem_, this});
    loop.run();
    if (has_frag_job(next_frag_) || frag_busy_) {
      throw StallError("timing model stopped with work left: " + stall_reason());
    }
    end_commands_before(commands_.size());  // (checks their tiles fit their slots)
    result_.frame_time_ps = static_cast<double>(end_tick_.ps());
    result_.frame_cycles = static_cast<double>(core_.cycles_at(end_tick_).count());
    result_.address_layout = mem_.address_space().regions();
    result_.units.clear();
    for (std::size_t u = 0; u < kTimedUnitCount; ++u) {
      // The tile fetch is not a server: it is busy while any tile is being fetched.
      const bool fetch = u == index_of(TimedUnit::TileFetch);
      result_.units.push_back({std::string(kTimedUnitNames[u]), fetch ? fetch_busy_cycles_ : servers_[u].busy_cycles,
                               fetch ? 0.0 : servers_[u].stalled_cycles()});
    }
    for (std::size_t c = 0; c < busy_.size(); ++c) {
      for (std::size_t u = 0; u < kTimedUnitCount; ++u) {
        if (!busy_[c][u].intervals().empty()) result_.commands[c].unit_busy.push_back({result_.units[u].name, busy_[c][u].intervals()});
      }
    }
    for (std::uint32_t ch = 0; ch < mem_.dram().channels(); ++ch) {
      UnitBusy bus{"dram.ch" + std::to_string(ch), {}};
      for (const BusyInterval& i : mem_.dram().bus_busy(ch).intervals()) {
        bus.intervals.push_back({i.start_cycle / core_.period_ps(), i.end_cycle / core_.period_ps(), i.busy_cycles / core_.period_ps()});
      }
      result_.dram_bus.push_back(std::move(bus));
    }
    result_.dram = mem_.traffic();
    // The last frame's bytes include the writes still queued at its end, drained by now.
    if (!result_.frames.empty()) result_.frames.back().dram_bytes_at_end = result_.dram.total_read() + result_.dram.total_written();
    result_.requested = mem_.requested();
    result_.memory_units = mem_.snapshot();
    result_.memory = mem_.stats();
    if (result_.frames.size() > 1) result_.frames.back().memory_at_end = result_.memory;  // at the run's end, as its bytes
    result_.events = eq_.events_executed();
    for (const CommandWork* c : commands_) {
      const CommandWork& cmd = *c;
      for (const auto& r : cmd.renders) {
        for (const auto& t : r.tiles) {
          result_.texture_line_accesses += t.texture_line_accesses;
          result_.texture_footprint_lines += t.texture_lines.size();
        }
      }
      result_.texture_line_accesses += cmd.texture_line_accesses;
      result_.texture_footprint_lines += cmd.texture_lines.size();
    }
    result_.texture_cache_misses = mem_.texture_cache().class_stats(DramClass::Textures).read_misses.value();
    result_.tiles = tile_records_.take();
    return std::move(result_);
  }

  std::string_view name() const override { return "gpu_scheduler"; }
  /// (Jobs not yet taken from the feed are not pending: taking them is what starting them does.)
  bool has_pending_work() const override { return next_frag_ < frag_jobs_.size() || frag_busy_; }
  /// Jobs and tiles finished, plus the time itself while a unit is working off reserved work: a
  /// tile whose shading takes longer than the watchdog window (thousands of lights per pixel) is
  /// progress, not a livelock.
  std::uint64_t progress() const override {
    const Tick now = eq_.now();
    bool working = false;
    for (const Server& s : servers_) working = working || s.free_at > now;
    return next_frag_ * 1000000 + tiles_done_ + next_bin_ + (working ? static_cast<std::uint64_t>(now.ps()) : 0);
  }
  std::string stall_reason() const override {
    return "fragment job " + std::to_string(next_frag_) + "/" + std::to_string(frag_jobs_.size()) + ", binning job " +
           std::to_string(next_bin_) + "/" + std::to_string(bin_jobs_.size()) + ", tiles done " + std::to_string(tiles_done_) +
           "/" + std::to_string(tiles_.size()) + ", tiles in flight " + std::to_string(in_flight_);
  }


 private:
  struct Job {
    std::size_t command;
    int render;  ///< -1 for a dispatch
  };

  /// Takes the next piece of the frame from the feed, waiting until the functional run has
  /// produced it: the current pass's next render (places its vertex range; adds its binning and
  /// fragment jobs) or, when the pass has no more, the next command (ends the previous one in the
  /// address map, places the new one; a dispatch adds its fragment job). False when the frame has
  /// no more.
  bool take_next() {
    while (true) {
      if (more_renders_) {
        const std::size_t c = commands_.size() - 1;
        const std::size_t r = renders_[c].size();
        if (const RenderWork* rw = feed_.wait_render(c, r)) {
          renders_[c].push_back(rw);
          map_.add_render(c, *rw);
          // Every render is a binning job and a fragment job.
          bin_jobs_.push_back({c, static_cast<int>(r)});
          frag_jobs_.push_back({c, static_cast<int>(r)});
          bin_done_.push_back(false);
          frag_done_.push_back(false);
          return true;
        }
        more_renders_ = false;
      }
      // The last command announced: nothing follows (no need to wait for the frame to end).
      if (commands_.size() >= feed_.expected_commands()) return false;
      const CommandWork* cmd = feed_.wait_for(commands_.size());
      if (cmd == nullptr) return false;
      // (The previous command may still be rendering: it ends in the address map when the
      // first fragment job after it starts, end_commands_before.)
      const std::size_t c = commands_.size();
      note_frame(*cmd);
      commands_.push_back(cmd);
      renders_.emplace_back();
      map_.add_command(*cmd);
      // A later frame's commands are told apart from the first's of the same name.
      result_.commands.push_back({cmd->frame > 0 ? "frame" + std::to_string(cmd->frame) + "." + cmd->name : cmd->name, -1, 0, 0, {}});
      busy_.emplace_back(kTimedUnitCount, BusyIntervals(per_command_intervals_));
      if (cmd->is_dispatch) {  // a fragment job only
        frag_jobs_.push_back({c, -1});
        frag_done_.push_back(false);
        return true;
      }
      more_renders_ = true;
    }
  }
  /// Ends in the address map every command before `c` not ended yet (in order): what each wrote
  /// becomes readable by the commands after it (FrameAddressMap::end_command).
  void end_commands_before(std::size_t c) {
    while (map_.ended() < c) map_.end_command(*commands_[map_.ended()]);
  }
  /// Whether binning job `k` exists (taking work from the feed until it does or none is left).
  bool has_bin_job(std::size_t k) {
    while (k >= bin_jobs_.size()) {
      if (!take_next()) return false;
    }
    return true;
  }
  /// Whether fragment job `f` exists (as has_bin_job).
  bool has_frag_job(std::size_t f) {
    while (f >= frag_jobs_.size()) {
      if (!take_next()) return false;
    }
    return true;
  }

  double cycles_of(Tick t) const { return static_cast<double>(t.ps()) / core_.period_ps(); }
  Tick after_cycles(Tick start, double cycles) const {
    return core_.after(start, Cycles{static_cast<std::int64_t>(std::ceil(cycles))});
  }
  /// Reserves `cycles` on a server no earlier than `ready` for `command`'s work; returns the end tick.
  Tick reserve(Server& s, std::size_t command, Tick ready, double cycles) {
    const Tick start = std::max(ready, s.free_at);
    const Tick end = after_cycles(start, cycles);
    s.free_at = end;
    s.busy_cycles += cycles;
    if (cycles > 0) {
      busy_[command][index_of(s.unit)].add(cycles_of(start), cycles_of(start) + cycles, cycles);
      s.add_span(cycles_of(start), cycles_of(start) + cycles);
    }
    return end;
  }

  DmaStream* new_stream(Client c, bool write, DramClass cls) {
    return new_stream(c, write, cls, static_cast<std::uint32_t>(hw_.memory.stream_outstanding_requests));
  }
  /// A stream for a unit's transfer: a finished one reused when there is one (a frame starts tens
  /// of thousands of them, few at once; keeping each to the end cost its allocations and, on the
  /// timing model's serial tail, their release: 1.5-4.5 ms at 1080p).
  DmaStream* new_stream(Client c, bool write, DramClass cls, std::uint32_t outstanding) {
    if (!idle_streams_.empty()) {
      DmaStream* s = idle_streams_.back();
      idle_streams_.pop_back();
      s->reset(c, write, cls, outstanding);
      return s;
    }
    streams_.push_back(std::make_unique<DmaStream>(eq_, mem_, c, write, cls, outstanding));
    streams_.back()->recycle_into(&idle_streams_);
    return streams_.back().get();
  }

  // ---- frames of a sequence ----------------------------------------------------------------
  /// Records the frame `cmd` belongs to when it is taken: the frames come in order, each with its
  /// first fragment job next.
  void note_frame(const CommandWork& cmd) {
    const auto fr = static_cast<std::size_t>(cmd.frame);
    if (fr < result_.frames.size()) return;
    if (cmd.frame < 0 || fr != result_.frames.size()) {
      throw std::logic_error("timing model: command " + cmd.name + " of frame " + std::to_string(cmd.frame) +
                             " follows frame " + std::to_string(result_.frames.size() - 1));
    }
    result_.frames.push_back({-1.0, 0.0, 0, {}});
    frame_first_frag_.push_back(frag_jobs_.size());
    frame_wake_.push_back(false);
  }
  /// Whether frame `fr`'s work may start now: with gpu.frames_in_flight = 1 once every fragment
  /// job of the frames before it has finished; with gpu.frame_period_us, no earlier than `fr`
  /// periods (a wake-up is scheduled then).
  bool frame_may_start(int fr) {
    if (fr <= 0) return true;
    const auto k = static_cast<std::size_t>(fr);
    if (hw_.gpu.frames_in_flight <= 1) {
      const std::size_t first = frame_first_frag_[k];
      if (first > 0 && !frag_done_[first - 1]) return false;
    }
    if (hw_.gpu.frame_period_us > 0) {
      const Tick at{static_cast<std::int64_t>(std::llround(hw_.gpu.frame_period_us * 1e6 * fr))};
      if (eq_.now() < at) {
        if (!frame_wake_[k]) {
          frame_wake_[k] = true;
          eq_.schedule(at, [this] {
            try_start_binning();
            try_start_fragment();
          });
        }
        return false;
      }
    }
    return true;
  }
  void frame_started(int fr) {
    FrameTime& f = result_.frames[static_cast<std::size_t>(fr)];
    if (f.start_cycle < 0) f.start_cycle = cycles_of(eq_.now());
  }

  // ---- binning -------------------------------------------------------------------------------
  void try_start_binning() {
    if (binning_busy_) return;
    const std::size_t k = next_bin_;
    // Two parameter buffers: job k reuses the buffer of job k-2, free once its tiles are done.
    // Checked before asking for job k: with the timing model beside the functional run, the
    // functional run may not have binned it yet, and the answer is not needed before the buffer
    // is free (the same schedule either way; the timing model goes on with the tiles meanwhile).
    if (k >= 2 && !frag_done_of_bin(k - 2)) return;
    // A partial render's successor needs the buffer the partial render just used: wait for it.
    // Checked before asking for job k too (job k - 1 partial: job k is its successor): the
    // functional run bins the successor only after the partial render's tiles, which the timing
    // model may then time meanwhile (forward_multipass at 2 threads waited 1.2 s here, 1080p).
    if (k >= 1 && partial_render_not_done(k - 1)) return;
    if (!has_bin_job(k)) return;
    const Job& j = bin_jobs_[k];
    const RenderWork& rw = *renders_[j.command][static_cast<std::size_t>(j.render)];
    if (j.render > 0 && !frag_done_of_bin(k - 1)) return;
    if (!frame_may_start(commands_[j.command]->frame)) return;
    binning_busy_ = true;
    ++next_bin_;
    const BinningWork& b = rw.binning;
    const Tick start = eq_.now();
    if (result_.commands[j.command].start_cycle < 0) result_.commands[j.command].start_cycle = cycles_of(start);
    frame_started(commands_[j.command]->frame);
    const Tick compute_end = reserve_geometry(b, j.command, start);
    auto pending = std::make_shared<int>(1);
    auto finish = [this, k, compute_end, pending]() {
      if (--*pending > 0) return;
      const Tick end = std::max(eq_.now(), compute_end);
      eq_.schedule(end, [this, k, compute_end] {
        // Time spent waiting for memory after the binning work itself was done.
        server(TimedUnit::Binning).add_span(cycles_of(compute_end), cycles_of(eq_.now()));
        bin_done_[k] = true;
        binning_busy_ = false;
        result_.commands[bin_jobs_[k].command].binning_end_cycle = cycles_of(eq_.now());
        try_start_binning();
        try_start_fragment();
      });
    };
    *pending += stream_geometry(b, j.command, static_cast<std::size_t>(j.render), finish);
    if (b.pb_write_bytes > 0) {
      DmaStream* s = new_stream(Client::Tiler, true, DramClass::ParameterBuffer);
      s->add(map_.parameter_buffer(k), b.pb_write_bytes);
      ++*pending;
      s->start(finish);
    }
    finish();
  }

  /// Fixed-function geometry (and tiling) on the binning engine from `start`; the vertex shaders
  /// run on the unified shading clusters, competing with the fragment and compute work queued
  /// there. Returns when both are done.
  Tick reserve_geometry(const BinningWork& b, std::size_t command, Tick start) {
    const double cycles = std::max({static_cast<double>(b.primitives_in) / hw_.geometry.primitives_per_clock,
                                    static_cast<double>(b.primitives_binned) / hw_.tiling.primitives_per_clock,
                                    static_cast<double>(b.vertex_fetch_bytes + b.index_fetch_bytes) / hw_.geometry.vertex_fetch_bytes_per_clock});
    return std::max(reserve(server(TimedUnit::Binning), command, start, cycles),
                    reserve(server(TimedUnit::Usc), command, start, static_cast<double>(b.vertex_alu_ops) / alu_rate_));
  }

  /// Starts the vertex and index fetch of `b`, work of render `render` of `command` (one
  /// sequential stream each, following the render's previous geometry, imr's earlier batches, in
  /// its vertex range); each calls `done` when finished. Returns how many streams were started.
  int stream_geometry(const BinningWork& b, std::size_t command, std::size_t render, const std::function<void()>& done) {
    if (b.vertex_fetch_bytes + b.index_fetch_bytes == 0) return 0;
    if (vertex_cursor_.size() <= command) vertex_cursor_.resize(command + 1);
    if (vertex_cursor_[command].size() <= render) vertex_cursor_[command].resize(render + 1, 0);
    std::uint64_t& cursor = vertex_cursor_[command][render];
    const std::uint64_t base = map_.vertices(command, render);
    DmaStream* s = new_stream(Client::Geometry, false, DramClass::Vertices);
    if (b.vertex_fetch_bytes) s->add(base + cursor, b.vertex_fetch_bytes);
    cursor += b.vertex_fetch_bytes;
    DmaStream* si = new_stream(Client::Geometry, false, DramClass::Indices);
    if (b.index_fetch_bytes) si->add(base + cursor, b.index_fetch_bytes);
    cursor += b.index_fetch_bytes;
    s->start(done);
    si->start(done);
    return 2;
  }

  /// gpu.mode=imr: streams a batch's ROP cache misses and write-backs through the SLC, one stream
  /// per direction and class (in their order within each); each calls `done` when finished.
  /// Returns how many streams were started.
  int stream_rop(const std::vector<FramebufferAccess>& accesses, const std::function<void()>& done) {
    std::map<std::pair<bool, DramClass>, DmaStream*> streams;
    for (const FramebufferAccess& a : accesses) {
      DmaStream*& s = streams[{a.write, a.cls}];
      if (!s) s = new_stream(Client::Rop, a.write, a.cls);
      s->add(map_.rop_framebuffer() + a.offset, a.bytes);
    }
    for (auto& [key, s] : streams) s->start(done);
    return static_cast<int>(streams.size());
  }

  /// Whether binning job `bin_index` (taken) is a partial render whose tiles are not all done.
  bool partial_render_not_done(std::size_t bin_index) const {
    const Job& b = bin_jobs_[bin_index];
    return b.render >= 0 && renders_[b.command][static_cast<std::size_t>(b.render)]->partial && !frag_done_of_bin(bin_index);
  }
  bool frag_done_of_bin(std::size_t bin_index) const {
    const Job& b = bin_jobs_[bin_index];
    for (std::size_t f = 0; f < frag_jobs_.size(); ++f) {
      if (frag_jobs_[f].command == b.command && frag_jobs_[f].render == b.render) return frag_done_[f];
    }
    return true;
  }
  std::size_t bin_index_of(const Job& j) const {
    for (std::size_t b = 0; b < bin_jobs_.size(); ++b) {
      if (bin_jobs_[b].command == j.command && bin_jobs_[b].render == j.render) return b;
    }
    return 0;
  }

  // ---- fragment jobs (renders and dispatches) --------------------------------------------------
  void try_start_fragment() {
    if (frag_busy_ || !has_frag_job(next_frag_)) return;
    const Job& j = frag_jobs_[next_frag_];
    if (j.render >= 0 && !bin_done_[bin_index_of(j)]) return;
    // (A render's frame was let start by its binning; a dispatch has none.)
    if (j.render < 0 && !frame_may_start(commands_[j.command]->frame)) return;
    frag_busy_ = true;
    const std::size_t f = next_frag_++;
    // Fragment jobs run in order: every command before this one has finished rendering, so what
    // it wrote is known (its tiles all published) before this one reads any of it.
    end_commands_before(j.command);
    // A dispatch may be opened before it has run (the functional run bins the pass after it
    // first): its content is needed now.
    if (j.render < 0) feed_.wait_complete(j.command);
    const CommandWork& cmd = *commands_[j.command];
    // Its buffer area, from its bytes, known by now (FrameAddressMap::place_buffers).
    if (j.render <= 0) map_.place_buffers(j.command, cmd);
    if (result_.commands[j.command].start_cycle < 0) result_.commands[j.command].start_cycle = cycles_of(eq_.now());
    frame_started(cmd.frame);
    if (j.render < 0) {
      start_dispatch(f, cmd);
    } else {
      start_render(f, cmd, static_cast<std::size_t>(j.render));
    }
  }

  void fragment_finished(std::size_t f) {
    frag_done_[f] = true;
    frag_busy_ = false;
    result_.commands[frag_jobs_[f].command].end_cycle = cycles_of(eq_.now());
    end_tick_ = std::max(end_tick_, eq_.now());
    // Fragment jobs finish in order: the frame's end so far is its last one's.
    FrameTime& frame = result_.frames[static_cast<std::size_t>(commands_[frag_jobs_[f].command]->frame)];
    frame.end_cycle = cycles_of(eq_.now());
    // A sequence's frame ends are snapshots of the memory system (a single frame's is the run's end).
    if (work_.frames > 1) {
      const DramTraffic moved = mem_.traffic();
      frame.dram_bytes_at_end = moved.total_read() + moved.total_written();
      frame.memory_at_end = mem_.energy_stats();
    }
    try_start_binning();
    try_start_fragment();
  }

  void start_dispatch(std::size_t f, const CommandWork& cmd) {
    const Tick start = eq_.now();
    const std::size_t command = frag_jobs_[f].command;
    const Tick compute_end = std::max(reserve(server(TimedUnit::Usc), command, start, static_cast<double>(cmd.compute_alu_ops) / alu_rate_),
                                      reserve(server(TimedUnit::Texture), command, start, static_cast<double>(cmd.compute_texels) / tex_rate_));
    auto pending = std::make_shared<int>(1);
    auto finish = [this, f, compute_end, pending]() {
      if (--*pending > 0) return;
      eq_.schedule(std::max(eq_.now(), compute_end), [this, f] { fragment_finished(f); });
    };
    const std::uint64_t base = map_.buffers(frag_jobs_[f].command);
    std::uint64_t offset = 0;
    for (int write = 0; write < 2; ++write) {
      for (std::size_t c = 0; c < kDramClassCount; ++c) {
        const std::uint64_t bytes = write ? cmd.write_bytes[c] : cmd.read_bytes[c];
        if (bytes == 0) continue;
        DmaStream* s = new_stream(Client::Compute, write != 0, static_cast<DramClass>(c));
        // Reads of what an earlier command wrote (a G-buffer, depth, light lists) come from where
        // it was written; anything else from the dispatch's own area.
        const std::vector<ByteRange> from =
            write ? std::vector<ByteRange>{} : map_.produced(frag_jobs_[f].command, static_cast<DramClass>(c), -1, bytes, bytes);
        if (from.empty()) s->add(base + offset, bytes);
        for (const ByteRange& r : from) s->add(r.offset, r.bytes);
        offset += bytes;
        ++*pending;
        s->start(finish);
      }
    }
    // The material fetches' texture lines go through the texture cache as a tile's footprint does
    // (one request per line); every USC's tasks are resident, so the texture units' cap is in flight.
    if (!cmd.texture_lines.empty()) {
      DmaStream* s = new_stream(Client::Texture, false, DramClass::Textures,
                                static_cast<std::uint32_t>(hw_.texture.outstanding_requests));
      for (const std::uint64_t l : cmd.texture_lines) s->add(map_.textures() + l, texture_line_bytes_);
      ++*pending;
      s->start(finish);
    }
    finish();
  }

  void start_render(std::size_t f, const CommandWork& cmd, std::size_t r) {
    render_ = renders_[frag_jobs_[f].command][r];
    render_job_ = f;
    render_command_ = frag_jobs_[f].command;
    render_index_ = r;
    render_pb_base_ = map_.parameter_buffer(bin_index_of(frag_jobs_[f]));
    tiles_.assign(feed_.tile_count(frag_jobs_[f].command, r), TileState{});
    next_dispatch_ = 0;
    next_isp_ = 0;
    tiles_done_ = 0;
    in_flight_ = 0;
    isp_busy_ = false;
    // Buffers a pass reads once (lights, light lists) at the start of its first render.
    if (r == 0) {
      std::uint64_t offset = 0;
      for (std::size_t c = 0; c < kDramClassCount; ++c) {
        if (cmd.read_bytes[c] == 0) continue;
        DmaStream* s = new_stream(Client::Texture, false, static_cast<DramClass>(c));
        s->add(map_.buffers(render_command_) + offset, cmd.read_bytes[c]);
        offset += cmd.read_bytes[c];
        s->start([] {});
      }
    }
    if (tiles_.empty()) {
      fragment_finished(f);
      return;
    }
    dispatch_tiles();
  }

  /// Where a tile of the current render loads from (`store`: stores to): its pass's framebuffer
  /// slot, or the partial renders' slot for what a partial render stores and the renders after
  /// one reload (and read as images).
  std::uint64_t tile_address(const TileWork& t, bool store = false) const {
    return map_.tile(render_command_, t, in_partial_slot(store));
  }
  bool in_partial_slot(bool store) const { return store ? render_->partial : render_index_ > 0; }
  int tile_index(const TileWork& t) const { return t.tile_y * work_.tiles_x + t.tile_x; }

  void dispatch_tiles() {
    while (in_flight_ < static_cast<std::size_t>(hw_.isp.tiles_in_flight) && next_dispatch_ < tiles_.size()) {
      const std::size_t i = next_dispatch_++;
      ++in_flight_;
      TileState& ts = tiles_[i];
      // The tile as the functional run merged it (waiting for it if it has not yet).
      ts.work = feed_.wait_tile(render_command_, render_index_, i);
      if (ts.work == nullptr) throw std::runtime_error("timing model: the functional run ended before " + result_.commands[render_command_].name + "'s tiles");
      const TileWork& t = *ts.work;
      ts.fetch_start = eq_.now();
      if (fetches_in_flight_++ == 0) fetch_busy_since_ = eq_.now();
      ts.pending_streams = 1;
      auto on_stream = [this, i]() {
        if (--tiles_[i].pending_streams > 0) return;
        tiles_[i].fetched = true;
        // Busy while at least one tile is being fetched (several overlap: their union, not their sum).
        if (--fetches_in_flight_ == 0) {
          const double from = cycles_of(fetch_busy_since_), to = cycles_of(eq_.now());
          fetch_busy_cycles_ += to - from;
          busy_[render_command_][index_of(TimedUnit::TileFetch)].add(from, to, to - from);
        }
        advance_isp();
      };
      if (work_.immediate) {
        // imr: the batch's geometry is processed as it goes down the pipeline: the next batches'
        // geometry overlaps this one's rasterisation and shading (up to isp.tiles_in_flight).
        const Tick geometry_end = reserve_geometry(t.geometry, render_command_, eq_.now());
        ts.pending_streams += 1 + stream_geometry(t.geometry, render_command_, render_index_, on_stream);
        eq_.schedule(geometry_end, [on_stream] { on_stream(); });
      }
      if (!t.pb_reads.empty()) {
        DmaStream* s = new_stream(Client::Isp, false, DramClass::ParameterBuffer);
        for (const auto& br : t.pb_reads) s->add(render_pb_base_ + br.offset, br.bytes);
        ++ts.pending_streams;
        s->start(on_stream);
      }
      std::uint64_t offset = 0;
      for (std::size_t c = 0; c < kDramClassCount; ++c) {
        if (t.load_bytes[c] == 0) continue;
        DmaStream* s = new_stream(Client::PixelBackEnd, false, static_cast<DramClass>(c));
        // A load op reads what an earlier command stored for this tile, where it stored it; a
        // later render's reloads (after a partial render) read this pass's own stores.
        const std::vector<ByteRange> from =
            render_index_ == 0 ? map_.produced(render_command_, static_cast<DramClass>(c), tile_index(t), t.load_bytes[c], t.load_bytes[c])
                               : std::vector<ByteRange>{};
        if (from.empty()) s->add(tile_address(t) + offset, t.load_bytes[c]);
        for (const ByteRange& r : from) s->add(r.offset, r.bytes);
        offset += t.load_bytes[c];
        ++ts.pending_streams;
        s->start(on_stream);
      }
      eq_.schedule(eq_.now(), [on_stream] { on_stream(); });
    }
  }

  /// Tiles enter the ISP in order once fetched. A resolved tile waits in the ISP for task slots
  /// on the USCs (usc.tasks_in_flight), and the ISP does not start the next tile meanwhile: that
  /// wait is the ISP's stall. Several tiles are resident on the USCs at once, as many as their
  /// tasks fit in the slots.
  void advance_isp() {
    if (isp_busy_ || next_isp_ >= tiles_.size() || !tiles_[next_isp_].fetched) return;
    const std::size_t i = next_isp_++;
    const TileWork& t = *tiles_[i].work;
    // Plus the shading the ISP waited for at punch-through depth resolves (models/isp.hpp).
    const double isp_cycles = std::max(static_cast<double>(t.primitives), static_cast<double>(t.samples) / raster_rate_) +
                              std::max(static_cast<double>(t.isp_wait_alu_ops) / alu_rate_, static_cast<double>(t.isp_wait_texels) / tex_rate_);
    isp_busy_ = true;
    const Tick raster_end = reserve(server(TimedUnit::Isp), render_command_, eq_.now(), isp_cycles);
    if (t.rop_depth.empty()) {
      eq_.schedule(raster_end, [this, i] { request_slots(i); });
      return;
    }
    // imr: the depth tests' cache misses are fetched (and evicted lines written back) while the
    // ISP works; it passes the batch on when both are done.
    auto pending = std::make_shared<int>(1);
    auto finish = [this, i, raster_end, pending]() {
      if (--*pending > 0) return;
      const Tick end = std::max(eq_.now(), raster_end);
      if (end > raster_end) server(TimedUnit::Isp).add_span(cycles_of(raster_end), cycles_of(end));
      eq_.schedule(end, [this, i] { request_slots(i); });
    };
    *pending += stream_rop(t.rop_depth, finish);
    finish();
  }

  /// Quads of a tile whose tasks have work to run: a task of a shader with nothing to run (a
  /// depth-only shader: no ALU op, fetch or output) retires as soon as it is issued, so it holds no
  /// slot while the tile's other tasks compute and wait for memory.
  static std::uint64_t working_quads(const TileWork& t) { return t.quads - std::min(t.idle_quads, t.quads); }
  /// Tasks of a tile's fragment shading that stay resident: its working quads' lanes in tasks of
  /// usc.threads_per_task.
  std::uint64_t tasks_of(const TileWork& t) const {
    const auto threads = static_cast<std::uint64_t>(hw_.usc.threads_per_task);
    return (working_quads(t) * kLanesPerQuad + threads - 1) / threads;
  }

  void request_slots(std::size_t i) {
    const Tick resolved = eq_.now();
    TileState& ts = tiles_[i];
    ts.slots = slots_.slots_for(tasks_of(*ts.work));
    slots_.acquire(ts.slots, [this, i, resolved] {
      server(TimedUnit::Isp).add_span(cycles_of(resolved), cycles_of(eq_.now()));
      isp_busy_ = false;
      --in_flight_;  // the tile has left the ISP: the tile fetch may bring the next one
      start_shading(i);
      dispatch_tiles();
      advance_isp();
    });
  }

  /// A resident tile's shading: its ALU work on the clusters and its filtering on the texture
  /// units (throughput shared, in arrival order, with every other resident tile, the vertex
  /// shaders and compute), while its texture footprint streams through the texture cache with
  /// the lines of its resident tasks in flight (up to texture.outstanding_requests): with few
  /// tasks the reads' latency is exposed, with many it hides behind the other tasks' work.
  void start_shading(std::size_t i) {
    const TileWork& t = *tiles_[i].work;
    TileState& ts = tiles_[i];
    const Tick now = eq_.now();
    ts.usc_end = std::max({reserve(server(TimedUnit::Usc), render_command_, now, static_cast<double>(t.alu_ops) / alu_rate_),
                           reserve(server(TimedUnit::Texture), render_command_, now, static_cast<double>(t.texels) / tex_rate_),
                           reserve(server(TimedUnit::TileBuffer), render_command_, now, static_cast<double>(t.tile_buffer_bytes) / tile_buffer_rate_)});
    ts.pending_shading = 1;
    eq_.schedule(ts.usc_end, [this, i] { shading_part_done(i); });
    if (!t.texture_lines.empty()) {
      ++ts.pending_shading;
      fetch_textures(i);
    }
    if (t.spill_read_bytes + t.spill_write_bytes > 0) access_spill(i);
    read_images(i);
  }

  /// Stored images the shaders read at their own pixels (a G-buffer under light volumes): their
  /// loads go through the texture cache and the SLC like texture fetches, one line per resident
  /// task in flight, so their latency is exposed with few tasks and hidden with many. Data no
  /// earlier command produced is read from the tile's framebuffer slot, after its loads, cycling
  /// over the slot (the pass's own attachments in memory).
  void read_images(std::size_t i) {
    const TileWork& t = *tiles_[i].work;
    std::uint64_t offset = 0;
    for (auto b : t.load_bytes) offset += b;
    const auto outstanding = static_cast<std::uint32_t>(std::clamp<std::uint64_t>(
        tiles_[i].slots, 1, static_cast<std::uint64_t>(hw_.texture.outstanding_requests)));
    for (std::size_t c = 0; c < kDramClassCount; ++c) {
      const std::uint64_t bytes = t.image_read_bytes[c];
      if (bytes == 0) continue;
      const auto cls = static_cast<DramClass>(c);
      DmaStream* s = new_stream(Client::Texture, false, cls, outstanding);
      // The first lap over the stored data streams through the texture cache; when the lap fits
      // in it, the re-reads after it (light volumes over the same pixels) hit there, as a tile's
      // texture footprint is fetched once (fetch_textures): each counted as the request and L1
      // hits it would be, without simulating it; their filtering is the texture units'
      // throughput (start_shading). A lap larger than the cache, or no cache, and every read is
      // simulated (cycling over more than an LRU cache holds, they miss).
      std::uint64_t lap = map_.produced_bytes(render_command_, cls, tile_index(t));
      const Cache* l1 = mem_.l1_of(Client::Texture);
      const bool reuse = l1 != nullptr && lap <= l1->size_bytes();
      MemorySystem::L1Hits hits;
      bool produced = false;
      // From where the producer stored the tile's data (re-reads cycle over it), else from the
      // tile's own slot.
      map_.for_each_produced(render_command_, cls, tile_index(t), bytes, texture_line_bytes_, [&](std::uint64_t at, std::uint64_t n) {
        produced = true;
        if (!reuse || lap > 0) {
          s->add(at, n);
          lap -= std::min(lap, n);
          return;
        }
        DmaStream::for_each_request(at, n, [&](std::uint64_t a, std::uint32_t m) { hits.add(a, m, l1->line_bytes()); });
      });
      if (hits.requests > 0) mem_.count_l1_read_hits(Client::Texture, hits, cls);
      if (!produced) {
        const std::uint64_t slot = map_.tile_slot_bytes(render_command_, in_partial_slot(false));
        for (std::uint64_t off = 0; off < bytes;) {
          const std::uint64_t at = (offset + off) % slot;
          const std::uint64_t n = std::min({texture_line_bytes_, bytes - off, slot - at});
          s->add(tile_address(t) + at, n);
          off += n;
        }
      }
      offset += bytes;
      ++tiles_[i].pending_shading;
      s->start([this, i] {
        const Tick usc_end = tiles_[i].usc_end;
        if (eq_.now() > usc_end) server(TimedUnit::Usc).add_span(cycles_of(usc_end), cycles_of(eq_.now()));
        shading_part_done(i);
      });
    }
  }

  /// Tile-buffer bytes past the on-chip budget live in memory: the shaders write them and read
  /// them back with their own loads and stores, through the SLC, one line per resident task in
  /// flight, while the tile is resident (its slots held): the latency shows when tasks are few.
  void access_spill(std::size_t i) {
    const TileWork& t = *tiles_[i].work;
    const std::uint64_t base = map_.spill(render_command_, t);
    const auto outstanding = static_cast<std::uint32_t>(std::max<std::uint64_t>(1, tiles_[i].slots));
    for (int write = 0; write < 2; ++write) {
      const std::uint64_t bytes = write ? t.spill_write_bytes : t.spill_read_bytes;
      if (bytes == 0) continue;
      DmaStream* s = new_stream(Client::PixelBackEnd, write != 0, DramClass::Spill, outstanding);
      // Reads come back from where the writes went (the slot holds the larger of the two). One
      // USC load or store per line of the SLC it goes through.
      const auto line = static_cast<std::uint64_t>(hw_.cache.slc.line_bytes);
      for (std::uint64_t off = 0; off < bytes; off += line) s->add(base + off, std::min(line, bytes - off));
      ++tiles_[i].pending_shading;
      s->start([this, i] { shading_part_done(i); });
    }
  }

  void fetch_textures(std::size_t i) {
    const TileWork& t = *tiles_[i].work;
    // A task issues its texture reads together (a material's fetches do not depend on each other)
    // and waits for them: the lines in flight are the resident tasks' lines, a task's share of the
    // tile's per-quad line accesses (quads of one task share lines, so this is an upper bound).
    const auto quads_per_task = static_cast<std::uint64_t>(hw_.usc.threads_per_task) / kLanesPerQuad;
    // (Over the working quads: a quad with nothing to run fetches nothing.)
    const std::uint64_t quads = working_quads(t);
    const std::uint64_t lines_per_task =
        quads == 0 ? 1 : std::max<std::uint64_t>(1, (t.texture_line_accesses * std::max<std::uint64_t>(1, quads_per_task) + quads - 1) / quads);
    const auto outstanding = static_cast<std::uint32_t>(std::clamp<std::uint64_t>(
        std::max<std::uint64_t>(1, tiles_[i].slots) * lines_per_task, 1, static_cast<std::uint64_t>(hw_.texture.outstanding_requests)));
    DmaStream* s = new_stream(Client::Texture, false, DramClass::Textures, outstanding);
    const std::uint64_t line = texture_line_bytes_;
    // One request per line: the memory system looks each line up in the texture cache.
    for (const std::uint64_t l : t.texture_lines) s->add(map_.textures() + l, line);
    s->start([this, i] {
      const Tick usc_end = tiles_[i].usc_end;
      if (eq_.now() > usc_end) server(TimedUnit::Usc).add_span(cycles_of(usc_end), cycles_of(eq_.now()));
      shading_part_done(i);
    });
  }

  void shading_part_done(std::size_t i) {
    if (--tiles_[i].pending_shading > 0) return;
    slots_.release(tiles_[i].slots);
    store_queue_.push_back(i);
    pump_stores();
  }

  /// The pixel back end writes one tile at a time: its stores stream to memory while it formats
  /// them at writeback.bytes_per_clock; the next tile's stores start when both are done.
  void pump_stores() {
    if (store_busy_ || store_queue_.empty()) return;
    const std::size_t i = store_queue_.front();
    store_queue_.pop_front();
    store_busy_ = true;
    const TileWork& t = *tiles_[i].work;
    std::uint64_t store = 0;
    for (auto b : t.store_bytes) store += b;
    const Tick pbe_end = reserve(server(TimedUnit::PixelBackEnd), render_command_, eq_.now(), static_cast<double>(store) / hw_.writeback.bytes_per_clock);
    auto pending = std::make_shared<int>(1);
    auto finish = [this, i, pbe_end, pending]() {
      if (--*pending > 0) return;
      const Tick end = std::max(eq_.now(), pbe_end);
      if (end > pbe_end) server(TimedUnit::PixelBackEnd).add_span(cycles_of(pbe_end), cycles_of(end));
      eq_.schedule(end, [this, i] {
        store_busy_ = false;
        tile_done(i);
        pump_stores();
      });
    };
    std::uint64_t offset = 0;
    for (std::size_t c = 0; c < kDramClassCount; ++c) {
      if (t.store_bytes[c] == 0) continue;
      DmaStream* s = new_stream(Client::PixelBackEnd, true, static_cast<DramClass>(c));
      s->add(tile_address(t, true) + offset, t.store_bytes[c]);
      offset += t.store_bytes[c];
      ++*pending;
      s->start(finish);
    }
    *pending += stream_rop(t.rop_color, finish);  // imr: the colour writes' misses and write-backs
    finish();
  }

  void tile_done(std::size_t i) {
    tile_records_.add(render_command_, *tiles_[i].work, cycles_of(eq_.now()) - cycles_of(tiles_[i].fetch_start));
    ++tiles_done_;
    if (tiles_done_ == tiles_.size()) {
      fragment_finished(render_job_);
      return;
    }
    dispatch_tiles();
  }

  const HwConfig& hw_;
  WorkFeed& feed_;
  const FrameWork& work_;  ///< the frame's fields (its commands come from the feed: commands_)
  std::vector<const CommandWork*> commands_;  ///< taken from the feed so far, in order
  std::vector<std::vector<const RenderWork*>> renders_;  ///< per command: its renders taken so far
  bool more_renders_ = false;  ///< the latest command is a pass that may have renders not taken yet
  std::size_t per_command_intervals_ = 0;  ///< busy intervals kept per command and unit
  ClockDomain core_;
  EventQueue eq_;
  MemorySystem mem_;
  FrameAddressMap map_;
  TileRecordBook tile_records_;
  TimingResult result_;
  std::array<Server, kTimedUnitCount> servers_{};  ///< by TimedUnit (the tile fetch's entry unused)
  Server& server(TimedUnit u) { return servers_[index_of(u)]; }
  std::vector<std::vector<BusyIntervals>> busy_;  ///< per command and unit: when it worked for it
  TaskSlots slots_;  ///< resident tasks across the USCs (usc.count x usc.tasks_in_flight)
  bool isp_busy_ = false;  ///< the ISP is resolving a tile or holds one waiting for task slots
  double alu_rate_ = 1, tex_rate_ = 1, raster_rate_ = 1, tile_buffer_rate_ = 1;
  double fetch_busy_cycles_ = 0;
  std::size_t fetches_in_flight_ = 0;  ///< tiles between dispatch and fetched
  Tick fetch_busy_since_{0};           ///< when the current run of overlapping fetches began
  std::vector<std::unique_ptr<DmaStream>> streams_;  ///< every stream made (each reused once finished)
  std::vector<DmaStream*> idle_streams_;               ///< finished streams, for new_stream
  std::vector<Job> bin_jobs_, frag_jobs_;
  std::vector<bool> bin_done_, frag_done_;
  std::size_t next_bin_ = 0, next_frag_ = 0;
  bool binning_busy_ = false, frag_busy_ = false;
  Tick end_tick_{0};
  std::vector<std::size_t> frame_first_frag_;  ///< per frame of the sequence: its first fragment job
  std::vector<bool> frame_wake_;                ///< per frame: a wake-up at its period's start is scheduled
  std::vector<std::vector<std::uint64_t>> vertex_cursor_;  ///< per command and render: next byte of its vertex range to stream
  std::uint64_t texture_line_bytes_ = 0;  ///< cache.texture.line_bytes
  // The render whose tiles are in flight.
  const RenderWork* render_ = nullptr;
  std::size_t render_job_ = 0, render_command_ = 0;
  std::uint64_t render_pb_base_ = 0;
  std::vector<TileState> tiles_;
  std::size_t next_dispatch_ = 0, next_isp_ = 0, tiles_done_ = 0, in_flight_ = 0;
  std::size_t render_index_ = 0;  ///< which render of its pass the current one is
  std::deque<std::size_t> store_queue_;
  bool store_busy_ = false;
};

}  // namespace

TimingResult run_timing(const HwConfig& hw, const FrameWork& work, DramObserver* dram_observer) {
  WorkFeed feed(work);
  return run_timing(hw, feed, dram_observer);
}

TimingResult run_timing(const HwConfig& hw, WorkFeed& feed, DramObserver* dram_observer) {
  TimingSim sim(hw, feed);
  if (dram_observer != nullptr) sim.observe_dram(dram_observer);
  return sim.run();
}

}  // namespace tbdr
