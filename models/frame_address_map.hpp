#pragma once
// Where the timing model places a frame's data in the simulated address space: first the frame's
// regions known before any command runs (the textures, gpu.mode=imr's framebuffer, two parameter
// buffers of tiling.pb_capacity_bytes: binning of one render overlaps the tiles of the previous
// one), then per command, in trace order, when the timing model takes it: its framebuffer area
// (one slot per tile of CommandWork::tile_slot_bytes) and its spill slots; per render, when its
// binning is taken, its vertex and index range; and, in the address space's high range
// (AddressSpace::allocate_high), a command's buffer area (lights, light lists, compute buffers:
// its read and write bytes) when its first fragment job starts. A dispatch knows
// its bytes only once it has run, and so does a pass reading what one wrote (its light lists), so
// the regions of the commands after them cannot wait for those bytes: the timing model bins the
// pass after a dispatch while the pass before it still renders. A command's regions depend only on
// what is known when they are placed and on the regions placed before, so the timing model can
// place them while earlier tiles are still being simulated. Each range is placed in command order,
// so how the timing model's schedule interleaves the two (which every swept parameter changes)
// moves no address. Addresses decide cache sets and DRAM banks, so the layout is a pure function
// of the frame's work: the same work always gets the same addresses.
#include <algorithm>
#include <array>
#include <span>
#include <cstdint>
#include <string>
#include <vector>

#include "models/address_space.hpp"
#include "models/frame_work.hpp"

namespace tbdr {

/// The address map of one frame's regions: the frame's own first, then each command's as it is added.
class FrameAddressMap {
 public:
  /// Allocates the frame's regions in `space`: FrameWork::texture_bytes of textures,
  /// FrameWork::framebuffer_bytes of imr framebuffer, two parameter buffers of `pb_bytes`.
  FrameAddressMap(const FrameWork& frame, std::uint64_t pb_bytes, AddressSpace& space);
  /// Allocates the regions of `cmd`, the next command of the frame, from what is known when it
  /// is opened (its name, slots; not its bytes: place_buffers). Commands are added in trace
  /// order; a command may be added before the ones before it ended (the timing model bins a pass
  /// while the previous one still renders): what those write becomes its source when they end.
  void add_command(const CommandWork& cmd);
  /// Allocates the buffer area of added command `command` (`cmd`, with its read and write bytes
  /// final) when its first fragment job starts; once (later calls do nothing).
  void place_buffers(std::size_t command, const CommandWork& cmd);
  /// Allocates the vertex and index range of render `r` of `command` (renders in order, each once
  /// its binning is known; gpu.mode=imr's single render complete with its batches' geometry), and
  /// at the pass's first partial render its partial renders' slots.
  void add_render(std::size_t command, const RenderWork& r);
  /// Records what the complete `cmd` (the earliest command added that has not ended: commands
  /// end in order) wrote where, for the commands after it to read (produced), also those added
  /// already; throws std::logic_error if a tile loaded or stored more than its slot holds.
  void end_command(const CommandWork& cmd);
  /// Commands ended so far (the next to end is this index).
  std::size_t ended() const { return ended_; }
  /// Commands added so far.
  std::size_t commands() const { return fb_base_.size(); }

  /// Base of parameter buffer `which` (0 or 1: binning job k uses buffer k % 2).
  std::uint64_t parameter_buffer(std::size_t which) const { return pb_base_[which % 2]; }
  /// Base of render `r`'s vertex and index range (its binning, or its imr batches, stream their
  /// fetches one after another from there).
  std::uint64_t vertices(std::size_t command, std::size_t r) const { return vertex_base_[command][r]; }
  /// Base of the texture address space (FrameWork::texture_bytes; TileWork::texture_lines are offsets in it).
  std::uint64_t textures() const { return texture_base_; }
  /// Base of gpu.mode=imr's framebuffer (FramebufferAccess::offset is relative to it).
  std::uint64_t rop_framebuffer() const { return rop_framebuffer_base_; }
  /// Base of a command's buffer area (a dispatch's reads and writes, a pass's once-read buffers);
  /// throws std::logic_error before place_buffers.
  std::uint64_t buffers(std::size_t command) const;
  /// Base of one tile's framebuffer slot of a pass (loads and stores of all its classes follow
  /// each other): with `partial`, its slot for what partial renders store and the renders after
  /// them reload (allocated by add_render at the pass's first partial render).
  std::uint64_t tile(std::size_t command, const TileWork& t, bool partial = false) const;
  /// Bytes of a pass's framebuffer slot (CommandWork::tile_slot_bytes or partial_slot_bytes
  /// rounded up to whole units).
  std::uint64_t tile_slot_bytes(std::size_t command, bool partial = false) const {
    return partial ? partial_stride_[command] : fb_stride_[command];
  }
  /// Base of one tile's slot of tile-buffer bytes spilled to memory (pls.over_budget = spill).
  std::uint64_t spill(std::size_t command, const TileWork& t) const;

  /// Where `command` reads `bytes` of class `k` that an earlier command produced: the addresses
  /// that command wrote them to (the latest earlier command writing class `k`: a pass's tile
  /// stores, a dispatch's writes), cut into pieces of at most `piece` bytes. A tile's reads
  /// (`tile_index` >= 0) come from the same tile's stores of a pass (or the dispatch's data from
  /// the tile's share on); a dispatch's reads (`tile_index` < 0) from all of it in order. Reads
  /// beyond what was written cycle over it again (light volumes re-reading a tile's G-buffer hit
  /// in the caches as on hardware; the timing model counts the laps after the first as texture
  /// cache hits, `produced_bytes` giving a lap). Empty when nothing earlier wrote class `k` there: the reader
  /// then uses its own slot.
  std::vector<ByteRange> produced(std::size_t command, DramClass k, int tile_index, std::uint64_t bytes,
                                  std::uint64_t piece) const;
  /// produced()'s pieces handed to fn(offset, bytes) one by one, in order, without the list.
  template <class Fn>
  void for_each_produced(std::size_t command, DramClass k, int tile_index, std::uint64_t bytes, std::uint64_t piece,
                         Fn&& fn) const {
    std::uint64_t start = 0;
    const std::span<const ByteRange> src = sources(command, k, tile_index, bytes, piece, start);
    if (src.empty()) return;
    // Walk the ranges from `start`, piece by piece, until `bytes` are covered.
    std::size_t ri = 0;
    std::uint64_t in = start;
    while (ri < src.size() && in >= src[ri].bytes) in -= src[ri++].bytes;
    for (std::uint64_t done = 0; done < bytes;) {
      const ByteRange& r = src[ri];
      const std::uint64_t n = std::min({piece, r.bytes - in, bytes - done});
      fn(r.offset + in, n);
      done += n;
      in += n;
      if (in == r.bytes) {
        in = 0;
        ri = (ri + 1) % src.size();
      }
    }
  }
  /// Bytes of class `k` an earlier command produced where `produced` reads a tile's (or a
  /// dispatch's) data from: one lap of what it cycles over; 0 when nothing earlier wrote them.
  std::uint64_t produced_bytes(std::size_t command, DramClass k, int tile_index) const;

 private:
  /// Allocates region `name` of `command` (in the high range with `high`); in a later frame of a
  /// sequence, the region of that name an earlier frame allocated (AddressSpace::reuse_or_allocate).
  std::uint64_t place(std::size_t command, const std::string& name, std::uint64_t bytes, DramClass cls, bool high = false);
  /// end_command's record of command `c`'s writes (written_, last_writer_).
  void record_writes(std::size_t c, const CommandWork& cmd);
  /// The ranges produced() cycles over for a read of `bytes` in pieces of `piece` (empty: none)
  /// and where in them it starts; a dispatch's read of a pass's tiles is gathered in sources_.
  std::span<const ByteRange> sources(std::size_t command, DramClass k, int tile_index, std::uint64_t bytes, std::uint64_t piece,
                                     std::uint64_t& start) const;

  bool reuse_layout_ = false;  ///< the space began with FrameWork::address_layout: every frame reuses its regions
  AddressSpace& space_;
  int tiles_x_ = 1;
  std::uint64_t pb_base_[2] = {0, 0};
  std::uint64_t rop_framebuffer_base_ = 0;
  std::uint64_t texture_base_ = 0;
  bool immediate_ = false;  ///< FrameWork::immediate: a render's batches carry its geometry
  std::size_t ended_ = 0;   ///< commands ended (end_command), in order
  std::vector<std::uint64_t> fb_base_, fb_stride_, partial_base_, partial_stride_, cmd_base_, spill_base_, spill_stride_;
  std::vector<bool> buffers_placed_;  ///< per command: place_buffers ran
  mutable std::vector<ByteRange> sources_;  ///< sources()'s gathering of a pass's tile ranges
  std::vector<std::vector<std::uint64_t>> vertex_base_;  ///< per command and render
  std::vector<std::string> names_;                       ///< per command (its regions' names)
  std::vector<int> frame_;                               ///< per command: its frame of the sequence
  std::vector<std::uint64_t> tile_slots_;                ///< per command: its tiles' slots
  /// What one command wrote of one class: per tile index (passes) or one range (dispatches).
  struct Written {
    std::vector<ByteRange> tiles;  ///< by tile index; bytes 0 where the tile stored none
    ByteRange all;                 ///< a dispatch's range
    bool per_tile = false;
  };
  std::vector<std::array<Written, kDramClassCount>> written_;           ///< per command
  std::vector<std::array<int, kDramClassCount>> source_;                ///< per command: the writer it reads, or -1
  std::array<int, kDramClassCount> last_writer_{};                      ///< per class: the latest command writing it, or -1
};

}  // namespace tbdr
