#include "models/timing_model.hpp"

#include <algorithm>
#include <cmath>
#include <deque>
#include <functional>
#include <map>
#include <tuple>
#include <memory>

#include "models/memory_system.hpp"
#include "kernel/errors.hpp"
#include "kernel/event_queue.hpp"
#include "kernel/run_loop.hpp"
#include "kernel/time.hpp"

namespace tbdr {

namespace {

// Bytes per memory request a DMA stream issues: a stream cuts its ranges at 4 KB boundaries, as
// no AMBA AXI burst may cross a 4 KB address boundary (Arm, AMBA AXI protocol specification).
// How many of them a stream keeps in flight is memory.stream_outstanding_requests.
constexpr std::uint64_t kChunkBytes = 4096;
// Address layout of the regions the timing model allocates (addresses set cache sets and DRAM
// banks, so these are fixed: they must not move when a parameter is swept). Every region gets at
// least one 4 KB page, the address space's granule; per-tile framebuffer areas and command buffers
// are whole 64-byte units, the default cache line (not cache.*.line_bytes, which a sweep varies).
constexpr std::uint64_t kMinRegionBytes = 4096;
constexpr std::uint64_t kRegionAlignBytes = 64;

/// A FIFO server with a throughput: jobs reserve it in arrival order.
struct Server {
  std::string name;
  Tick free_at{0};
  double busy_cycles = 0;
  double stalled_cycles = 0;
};

class TimingSim;

/// Streams byte ranges of one traffic class to memory as chunked requests, a bounded number in
/// flight, retrying when the memory system pushes back; calls `done` when every byte completed.
class MemStream {
 public:
  MemStream(TimingSim& sim, Client client, bool write, DramClass cls, std::uint32_t outstanding)
      : sim_(sim), client_(client), write_(write), cls_(cls), outstanding_(outstanding) {}
  void add(std::uint64_t addr, std::uint64_t bytes);
  void start(std::function<void()> done);
  bool empty() const { return chunks_.empty(); }

 private:
  void pump();
  TimingSim& sim_;
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
};

/// Scheduling state of one tile of the current render.
struct TileState {
  Tick fetch_start{0};
  bool fetched = false;
  int pending_streams = 0;
  int pending_shading = 0;  ///< USC work and texture fetch still to finish
  Tick usc_end{0};
};

/// The scheduler of the frame's work; a Unit so the run loop's watchdog can name it when stuck.
class TimingSim final : public Unit {
 public:
  TimingSim(const HwConfig& hw, const FrameWork& work)
      : hw_(hw),
        work_(work),
        core_(ClockDomain::from_mhz("core", hw.gpu.core_clock_mhz)),
        mem_(hw, eq_, "mem") {
    isp_.name = "isp";
    usc_.name = "usc";
    pbe_.name = "pixel_back_end";
    binner_.name = "binning";
    alu_rate_ = static_cast<double>(hw.usc.count * hw.usc.lanes) * hw.usc.alu_ops_per_lane_per_clock;
    tex_rate_ = static_cast<double>(hw.texture.units) * hw.texture.texels_per_clock;
    raster_rate_ = static_cast<double>(hw.isp.samples_per_clock * hw.isp.raster_pipes);
    const std::uint64_t tile_px = static_cast<std::uint64_t>(hw.tiling.tile_width * hw.tiling.tile_height);
    usc_queue_tiles_ = std::max<std::uint64_t>(
        1, static_cast<std::uint64_t>(hw.usc.tasks_in_flight) * static_cast<std::uint64_t>(hw.usc.threads_per_task) / tile_px);
    texture_line_bytes_ = static_cast<std::uint64_t>(hw.cache.texture.line_bytes);
    allocate_regions();
  }

  TimingResult run() {
    // Jobs in command order: every render is a binning job and a fragment job; a dispatch is a
    // fragment job only.
    for (std::size_t c = 0; c < work_.commands.size(); ++c) {
      const auto& cmd = work_.commands[c];
      if (cmd.is_dispatch) {
        frag_jobs_.push_back({c, -1});
      } else {
        for (std::size_t r = 0; r < cmd.renders.size(); ++r) {
          bin_jobs_.push_back({c, static_cast<int>(r)});
          frag_jobs_.push_back({c, static_cast<int>(r)});
        }
      }
      result_.commands.push_back({cmd.name, -1, 0, 0});
    }
    bin_done_.assign(bin_jobs_.size(), false);
    frag_done_.assign(frag_jobs_.size(), false);
    eq_.schedule(Tick{0}, [this] {
      try_start_binning();
      try_start_fragment();
    });
    RunLoop loop(eq_, {&mem_, this});
    loop.run();
    if (next_frag_ < frag_jobs_.size() || frag_busy_) {
      throw StallError("timing model stopped with work left: " + stall_reason());
    }
    result_.frame_time_ps = static_cast<double>(end_tick_.ps());
    result_.frame_cycles = static_cast<double>(core_.cycles_at(end_tick_).count());
    result_.units = {{binner_.name, binner_.busy_cycles, binner_.stalled_cycles},
                     {"tile_fetch", fetch_busy_cycles_, 0},
                     {isp_.name, isp_.busy_cycles, isp_.stalled_cycles},
                     {usc_.name, usc_.busy_cycles, usc_.stalled_cycles},
                     {pbe_.name, pbe_.busy_cycles, pbe_.stalled_cycles}};
    result_.dram = mem_.traffic();
    mem_.collect(result_.memory_stats);
    result_.memory = mem_.stats();
    result_.events = eq_.events_executed();
    for (const auto& cmd : work_.commands) {
      for (const auto& r : cmd.renders) {
        for (const auto& t : r.tiles) {
          result_.texture_line_accesses += t.texture_line_accesses;
          result_.texture_footprint_lines += t.texture_lines.size();
        }
      }
    }
    result_.texture_cache_misses = mem_.texture_cache().class_stats(DramClass::Textures).read_misses.value();
    return std::move(result_);
  }

  std::string_view name() const override { return "gpu_scheduler"; }
  bool has_pending_work() const override { return next_frag_ < frag_jobs_.size() || frag_busy_; }
  std::uint64_t progress() const override { return next_frag_ * 1000000 + tiles_done_ + next_bin_; }
  std::string stall_reason() const override {
    return "fragment job " + std::to_string(next_frag_) + "/" + std::to_string(frag_jobs_.size()) + ", binning job " +
           std::to_string(next_bin_) + "/" + std::to_string(bin_jobs_.size()) + ", tiles done " + std::to_string(tiles_done_) +
           "/" + std::to_string(tiles_.size()) + ", tiles in flight " + std::to_string(in_flight_);
  }

  EventQueue& eq() { return eq_; }
  MemorySystem& mem() { return mem_; }
  void count_issued(DramClass c, bool write, std::uint64_t bytes) {
    if (write) {
      result_.issued.write(c, bytes);
    } else {
      result_.issued.read(c, bytes);
    }
  }

 private:
  struct Job {
    std::size_t command;
    int render;  ///< -1 for a dispatch
  };

  double cycles_of(Tick t) const { return static_cast<double>(t.ps()) / core_.period_ps(); }
  Tick after_cycles(Tick start, double cycles) const {
    return core_.after(start, Cycles{static_cast<std::int64_t>(std::ceil(cycles))});
  }
  /// Reserves `cycles` on a server no earlier than `ready`; returns the end tick.
  Tick reserve(Server& s, Tick ready, double cycles) {
    const Tick start = std::max(ready, s.free_at);
    const Tick end = after_cycles(start, cycles);
    s.free_at = end;
    s.busy_cycles += cycles;
    return end;
  }

  void allocate_regions() {
    auto& space = mem_.address_space();
    std::uint64_t pb_bytes = kMinRegionBytes, vertex_bytes = kMinRegionBytes, buffer_bytes = kMinRegionBytes;
    for (std::size_t c = 0; c < work_.commands.size(); ++c) {
      const auto& cmd = work_.commands[c];
      std::uint64_t cmd_bytes = 0;
      for (std::size_t k = 0; k < kDramClassCount; ++k) cmd_bytes += cmd.read_bytes[k] + cmd.write_bytes[k];
      buffer_bytes = std::max(buffer_bytes, cmd_bytes);
      std::uint64_t stride = kRegionAlignBytes;
      for (const auto& r : cmd.renders) {
        std::uint64_t extent = r.binning.pb_write_bytes;
        for (const auto& t : r.tiles) {
          for (const auto& br : t.pb_reads) extent = std::max(extent, br.offset + br.bytes);
          std::uint64_t l = 0, s = 0;
          for (std::size_t k = 0; k < kDramClassCount; ++k) {
            l += t.load_bytes[k];
            s += t.store_bytes[k];
          }
          stride = std::max(stride, std::max(l, s));
        }
        pb_bytes = std::max(pb_bytes, extent);
        vertex_bytes += r.binning.vertex_fetch_bytes + r.binning.index_fetch_bytes;
      }
      stride = (stride + kRegionAlignBytes - 1) / kRegionAlignBytes * kRegionAlignBytes;
      fb_stride_.push_back(stride);
      std::uint64_t max_tile = 1;
      for (const auto& r : cmd.renders) {
        for (const auto& t : r.tiles) max_tile = std::max<std::uint64_t>(max_tile, static_cast<std::uint64_t>(t.tile_y * work_.tiles_x + t.tile_x + 1));
      }
      fb_base_.push_back(cmd.is_dispatch ? 0 : space.allocate("framebuffer." + cmd.name, stride * max_tile, DramClass::Color));
      cmd_base_.push_back(space.allocate("buffers." + cmd.name, std::max<std::uint64_t>(cmd_bytes, kRegionAlignBytes), DramClass::Other));
    }
    if (work_.texture_bytes > 0) texture_base_ = space.allocate("textures", work_.texture_bytes, DramClass::Textures);
    pb_base_[0] = space.allocate("parameter_buffer.0", pb_bytes, DramClass::ParameterBuffer);
    pb_base_[1] = space.allocate("parameter_buffer.1", pb_bytes, DramClass::ParameterBuffer);
    vertex_base_ = space.allocate("vertex_and_index_buffers", vertex_bytes, DramClass::Vertices);
  }

  MemStream* new_stream(Client c, bool write, DramClass cls) {
    return new_stream(c, write, cls, static_cast<std::uint32_t>(hw_.memory.stream_outstanding_requests));
  }
  MemStream* new_stream(Client c, bool write, DramClass cls, std::uint32_t outstanding) {
    streams_.push_back(std::make_unique<MemStream>(*this, c, write, cls, outstanding));
    return streams_.back().get();
  }

  // ---- binning -------------------------------------------------------------------------------
  void try_start_binning() {
    if (binning_busy_ || next_bin_ >= bin_jobs_.size()) return;
    const std::size_t k = next_bin_;
    // Two parameter buffers: job k reuses the buffer of job k-2, free once its tiles are done.
    // A partial render's successor needs the buffer the partial render just used: wait for it.
    if (k >= 2 && !frag_done_of_bin(k - 2)) return;
    const Job& j = bin_jobs_[k];
    const RenderWork& rw = work_.commands[j.command].renders[static_cast<std::size_t>(j.render)];
    if (j.render > 0 && !frag_done_of_bin(k - 1)) return;
    binning_busy_ = true;
    ++next_bin_;
    const BinningWork& b = rw.binning;
    const double cycles = std::max({static_cast<double>(b.vertex_alu_ops) / alu_rate_,
                                    static_cast<double>(b.primitives_in) / hw_.geometry.primitives_per_clock,
                                    static_cast<double>(b.primitives_binned) / hw_.tiling.primitives_per_clock,
                                    static_cast<double>(b.vertex_fetch_bytes + b.index_fetch_bytes) / hw_.geometry.vertex_fetch_bytes_per_clock});
    const Tick start = eq_.now();
    if (result_.commands[j.command].start_cycle < 0) result_.commands[j.command].start_cycle = cycles_of(start);
    const Tick compute_end = reserve(binner_, start, cycles);
    auto pending = std::make_shared<int>(1);
    auto finish = [this, k, compute_end, pending]() {
      if (--*pending > 0) return;
      const Tick end = std::max(eq_.now(), compute_end);
      eq_.schedule(end, [this, k, compute_end] {
        // Time spent waiting for memory after the binning work itself was done.
        binner_.stalled_cycles += std::max(0.0, cycles_of(eq_.now()) - cycles_of(compute_end));
        bin_done_[k] = true;
        binning_busy_ = false;
        result_.commands[bin_jobs_[k].command].binning_end_cycle = cycles_of(eq_.now());
        try_start_binning();
        try_start_fragment();
      });
    };
    const std::uint64_t fetch = b.vertex_fetch_bytes + b.index_fetch_bytes;
    if (fetch > 0) {
      MemStream* s = new_stream(Client::Geometry, false, DramClass::Vertices);
      // Vertices and indices: one sequential stream per render (classes booked separately).
      if (b.vertex_fetch_bytes) s->add(vertex_base_ + vertex_cursor_, b.vertex_fetch_bytes);
      vertex_cursor_ += b.vertex_fetch_bytes;
      MemStream* si = new_stream(Client::Geometry, false, DramClass::Indices);
      if (b.index_fetch_bytes) si->add(vertex_base_ + vertex_cursor_, b.index_fetch_bytes);
      vertex_cursor_ += b.index_fetch_bytes;
      *pending += 2;
      s->start(finish);
      si->start(finish);
    }
    if (b.pb_write_bytes > 0) {
      MemStream* s = new_stream(Client::Tiler, true, DramClass::ParameterBuffer);
      s->add(pb_base_[k % 2], b.pb_write_bytes);
      ++*pending;
      s->start(finish);
    }
    finish();
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
    if (frag_busy_ || next_frag_ >= frag_jobs_.size()) return;
    const Job& j = frag_jobs_[next_frag_];
    if (j.render >= 0 && !bin_done_[bin_index_of(j)]) return;
    frag_busy_ = true;
    const std::size_t f = next_frag_++;
    const CommandWork& cmd = work_.commands[j.command];
    if (result_.commands[j.command].start_cycle < 0) result_.commands[j.command].start_cycle = cycles_of(eq_.now());
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
    try_start_binning();
    try_start_fragment();
  }

  void start_dispatch(std::size_t f, const CommandWork& cmd) {
    const Tick start = eq_.now();
    const double cycles = std::max(static_cast<double>(cmd.compute_alu_ops) / alu_rate_, static_cast<double>(cmd.compute_texels) / tex_rate_);
    const Tick compute_end = reserve(usc_, start, cycles);
    auto pending = std::make_shared<int>(1);
    auto finish = [this, f, compute_end, pending]() {
      if (--*pending > 0) return;
      eq_.schedule(std::max(eq_.now(), compute_end), [this, f] { fragment_finished(f); });
    };
    const std::uint64_t base = cmd_base_[frag_jobs_[f].command];
    std::uint64_t offset = 0;
    for (int write = 0; write < 2; ++write) {
      for (std::size_t c = 0; c < kDramClassCount; ++c) {
        const std::uint64_t bytes = write ? cmd.write_bytes[c] : cmd.read_bytes[c];
        if (bytes == 0) continue;
        MemStream* s = new_stream(Client::Compute, write != 0, static_cast<DramClass>(c));
        s->add(base + offset, bytes);
        offset += bytes;
        ++*pending;
        s->start(finish);
      }
    }
    finish();
  }

  void start_render(std::size_t f, const CommandWork& cmd, std::size_t r) {
    render_ = &cmd.renders[r];
    render_job_ = f;
    render_command_ = frag_jobs_[f].command;
    render_pb_base_ = pb_base_[bin_index_of(frag_jobs_[f]) % 2];
    tiles_.assign(render_->tiles.size(), TileState{});
    next_dispatch_ = 0;
    next_isp_ = 0;
    tiles_done_ = 0;
    in_flight_ = 0;
    usc_ends_.clear();
    // Buffers a pass reads once (lights, light lists) at the start of its first render.
    if (r == 0) {
      std::uint64_t offset = 0;
      for (std::size_t c = 0; c < kDramClassCount; ++c) {
        if (cmd.read_bytes[c] == 0) continue;
        MemStream* s = new_stream(Client::Texture, false, static_cast<DramClass>(c));
        s->add(cmd_base_[render_command_] + offset, cmd.read_bytes[c]);
        offset += cmd.read_bytes[c];
        s->start([] {});
      }
    }
    if (render_->tiles.empty()) {
      fragment_finished(f);
      return;
    }
    dispatch_tiles();
  }

  std::uint64_t tile_address(const TileWork& t) const {
    return fb_base_[render_command_] + static_cast<std::uint64_t>(t.tile_y * work_.tiles_x + t.tile_x) * fb_stride_[render_command_];
  }

  void dispatch_tiles() {
    while (in_flight_ < static_cast<std::size_t>(hw_.isp.tiles_in_flight) && next_dispatch_ < tiles_.size()) {
      const std::size_t i = next_dispatch_++;
      ++in_flight_;
      const TileWork& t = render_->tiles[i];
      TileState& ts = tiles_[i];
      ts.fetch_start = eq_.now();
      ts.pending_streams = 1;
      auto on_stream = [this, i]() {
        if (--tiles_[i].pending_streams > 0) return;
        tiles_[i].fetched = true;
        fetch_busy_cycles_ += cycles_of(eq_.now()) - cycles_of(tiles_[i].fetch_start);
        advance_isp();
      };
      if (!t.pb_reads.empty()) {
        MemStream* s = new_stream(Client::Isp, false, DramClass::ParameterBuffer);
        for (const auto& br : t.pb_reads) s->add(render_pb_base_ + br.offset, br.bytes);
        ++ts.pending_streams;
        s->start(on_stream);
      }
      std::uint64_t offset = 0;
      for (std::size_t c = 0; c < kDramClassCount; ++c) {
        if (t.load_bytes[c] == 0) continue;
        MemStream* s = new_stream(Client::PixelBackEnd, false, static_cast<DramClass>(c));
        s->add(tile_address(t) + offset, t.load_bytes[c]);
        offset += t.load_bytes[c];
        ++ts.pending_streams;
        s->start(on_stream);
      }
      eq_.schedule(eq_.now(), [on_stream] { on_stream(); });
    }
  }

  /// Tiles enter the ISP in order once fetched; their ISP, USC and pixel back end times are
  /// reserved on the servers, with the USC queue pushing back on the ISP.
  void advance_isp() {
    while (next_isp_ < tiles_.size() && tiles_[next_isp_].fetched) {
      const std::size_t i = next_isp_++;
      const TileWork& t = render_->tiles[i];
      const double isp_cycles = std::max(static_cast<double>(t.primitives), static_cast<double>(t.samples) / raster_rate_);
      Tick isp_end = reserve(isp_, eq_.now(), isp_cycles);
      // Backpressure: the USCs hold usc_queue_tiles_ tiles; wait for the oldest to leave.
      while (!usc_ends_.empty() && usc_ends_.front() <= isp_end) usc_ends_.pop_front();
      if (usc_ends_.size() >= usc_queue_tiles_) {
        const Tick free = usc_ends_[usc_ends_.size() - usc_queue_tiles_];
        if (free > isp_end) {
          isp_.stalled_cycles += cycles_of(free) - cycles_of(isp_end);
          isp_end = free;
          isp_.free_at = std::max(isp_.free_at, free);
        }
      }
      const double usc_cycles = std::max(static_cast<double>(t.alu_ops) / alu_rate_, static_cast<double>(t.texels) / tex_rate_);
      const Tick usc_start = std::max(isp_end, usc_.free_at);
      const Tick usc_end = reserve(usc_, isp_end, usc_cycles);
      usc_ends_.push_back(usc_end);
      TileState& ts = tiles_[i];
      ts.usc_end = usc_end;
      ts.pending_shading = 1;
      eq_.schedule(usc_end, [this, i] { shading_part_done(i); });
      // The tile's texture footprint streams through the texture cache while it shades; the tile
      // leaves the USCs when both its ALU work and its texture data are done.
      if (!t.texture_lines.empty()) {
        ++ts.pending_shading;
        eq_.schedule(usc_start, [this, i] { fetch_textures(i); });
      }
    }
  }

  void fetch_textures(std::size_t i) {
    const TileWork& t = render_->tiles[i];
    MemStream* s = new_stream(Client::Texture, false, DramClass::Textures,
                              static_cast<std::uint32_t>(hw_.texture.outstanding_requests));
    const std::uint64_t line = texture_line_bytes_;
    // Consecutive lines go as one range (the memory system still looks each line up).
    std::size_t k = 0;
    while (k < t.texture_lines.size()) {
      std::size_t e = k + 1;
      while (e < t.texture_lines.size() && t.texture_lines[e] == t.texture_lines[e - 1] + line) ++e;
      s->add(texture_base_ + t.texture_lines[k], (e - k) * line);
      k = e;
    }
    s->start([this, i] {
      const Tick usc_end = tiles_[i].usc_end;
      if (eq_.now() > usc_end) usc_.stalled_cycles += cycles_of(eq_.now()) - cycles_of(usc_end);
      shading_part_done(i);
    });
  }

  void shading_part_done(std::size_t i) {
    if (--tiles_[i].pending_shading > 0) return;
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
    const TileWork& t = render_->tiles[i];
    std::uint64_t store = 0;
    for (auto b : t.store_bytes) store += b;
    const Tick pbe_end = reserve(pbe_, eq_.now(), static_cast<double>(store) / hw_.writeback.bytes_per_clock);
    auto pending = std::make_shared<int>(1);
    auto finish = [this, i, pbe_end, pending]() {
      if (--*pending > 0) return;
      const Tick end = std::max(eq_.now(), pbe_end);
      if (end > pbe_end) pbe_.stalled_cycles += cycles_of(end) - cycles_of(pbe_end);
      eq_.schedule(end, [this, i] {
        store_busy_ = false;
        tile_done(i);
        pump_stores();
      });
    };
    std::uint64_t offset = 0;
    for (std::size_t c = 0; c < kDramClassCount; ++c) {
      if (t.store_bytes[c] == 0) continue;
      MemStream* s = new_stream(Client::PixelBackEnd, true, static_cast<DramClass>(c));
      s->add(tile_address(t) + offset, t.store_bytes[c]);
      offset += t.store_bytes[c];
      ++*pending;
      s->start(finish);
    }
    finish();
  }

  void tile_done(std::size_t i) {
    const TileWork& t = render_->tiles[i];
    std::uint64_t bytes = 0;
    for (std::size_t c = 0; c < kDramClassCount; ++c) bytes += t.load_bytes[c] + t.store_bytes[c];
    for (const auto& br : t.pb_reads) bytes += br.bytes;
    // One row per command and tile: strips and partial renders of the same tile add up.
    const auto key = std::make_tuple(render_command_, t.tile_x, t.tile_y);
    auto [it, inserted] = tile_rows_.try_emplace(key, result_.tiles.size());
    if (inserted) result_.tiles.push_back({static_cast<std::int64_t>(render_command_), t.tile_x, t.tile_y, 0, 0, 0});
    TileRecord& row = result_.tiles[it->second];
    row.cycles += cycles_of(eq_.now()) - cycles_of(tiles_[i].fetch_start);
    row.samples += static_cast<double>(t.samples);
    row.dram_bytes += static_cast<double>(bytes);
    --in_flight_;
    ++tiles_done_;
    if (tiles_done_ == tiles_.size()) {
      fragment_finished(render_job_);
      return;
    }
    dispatch_tiles();
  }

  const HwConfig& hw_;
  const FrameWork& work_;
  ClockDomain core_;
  EventQueue eq_;
  MemorySystem mem_;
  TimingResult result_;
  Server binner_, isp_, usc_, pbe_;
  double alu_rate_ = 1, tex_rate_ = 1, raster_rate_ = 1;
  std::uint64_t usc_queue_tiles_ = 1;
  double fetch_busy_cycles_ = 0;
  std::vector<std::unique_ptr<MemStream>> streams_;
  std::vector<Job> bin_jobs_, frag_jobs_;
  std::vector<bool> bin_done_, frag_done_;
  std::size_t next_bin_ = 0, next_frag_ = 0;
  bool binning_busy_ = false, frag_busy_ = false;
  Tick end_tick_{0};
  // Address space.
  std::uint64_t pb_base_[2] = {0, 0};
  std::uint64_t vertex_base_ = 0, vertex_cursor_ = 0;
  std::uint64_t texture_base_ = 0;
  std::uint64_t texture_line_bytes_ = 0;  // cache.texture.line_bytes
  std::vector<std::uint64_t> fb_base_, fb_stride_, cmd_base_;
  // The render whose tiles are in flight.
  const RenderWork* render_ = nullptr;
  std::size_t render_job_ = 0, render_command_ = 0;
  std::uint64_t render_pb_base_ = 0;
  std::vector<TileState> tiles_;
  std::size_t next_dispatch_ = 0, next_isp_ = 0, tiles_done_ = 0, in_flight_ = 0;
  std::deque<Tick> usc_ends_;
  std::deque<std::size_t> store_queue_;
  std::map<std::tuple<std::size_t, int, int>, std::size_t> tile_rows_;  ///< (command, x, y) -> row in result_.tiles
  bool store_busy_ = false;
};

void MemStream::add(std::uint64_t addr, std::uint64_t bytes) {
  sim_.count_issued(cls_, write_, bytes);
  while (bytes > 0) {
    const std::uint64_t n = std::min<std::uint64_t>(bytes, kChunkBytes - (addr % kChunkBytes));
    chunks_.push_back({addr, static_cast<std::uint32_t>(n)});
    addr += n;
    bytes -= n;
  }
}

void MemStream::start(std::function<void()> done) {
  done_ = std::move(done);
  if (chunks_.empty()) {
    sim_.eq().schedule(sim_.eq().now(), [this] { done_(); });
    return;
  }
  pump();
}

void MemStream::pump() {
  waiting_ = false;
  while (in_flight_ < outstanding_ && next_ < chunks_.size()) {
    const auto& ch = chunks_[next_];
    const bool ok = sim_.mem().issue(client_, ch.first, ch.second, write_, cls_, [this] {
      --in_flight_;
      if (++completed_ == chunks_.size()) {
        done_();
        return;
      }
      if (!waiting_) pump();
    });
    if (!ok) {
      waiting_ = true;
      sim_.mem().notify_when_ready([this] { pump(); });
      return;
    }
    ++in_flight_;
    ++next_;
  }
}

}  // namespace

TimingResult run_timing(const HwConfig& hw, const FrameWork& work) {
  TimingSim sim(hw, work);
  return sim.run();
}

}  // namespace tbdr
