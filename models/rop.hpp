#pragma once
// The render output unit (ROP) of an immediate-mode GPU (gpu.mode=imr): the depth/stencil and
// colour caches between the ISP and TSP and the framebuffer in memory. An immediate-mode GPU has no
// tile memory: every depth test reads the depth buffer, every colour write (and every blended one's
// read) goes to the colour buffer, through these caches; what misses is fetched from the system
// level cache and DRAM, what is evicted dirty is written back, and at the end of a pass the caches
// are flushed so that later commands find the images in memory.
//
// The caches are simulated here, functionally, in submission order (a cache's hits and misses
// depend only on the order of accesses, not on when they happen), so the timing model receives
// only their misses and write-backs (FramebufferAccess, in order) and streams those through the
// SLC and DRAM.
//
// Framebuffer layout: images are stored in blocks of kBlockPixels x kBlockPixels pixels (samples
// of a pixel together), the block-linear layout GPUs use so that a cache line holds a square of
// pixels rather than a sliver of one row; the images of the frame follow each other in one
// "framebuffer" address space (FrameWork::framebuffer_bytes).
#include <cstdint>
#include <map>
#include <string>
#include <vector>

#include "models/cache.hpp"
#include "models/frame_work.hpp"
#include "models/hw_config.hpp"
#include "trace/trace.hpp"
#include "kernel/stats.hpp"

namespace tbdr {

// Declared once: X(type, member = stored name, unit, Sum | Gauge, description).
#define TBDR_ROP_STATS(X) \
  X(Counter, depth_accesses, "accesses", Sum, "Depth/stencil cache line accesses (a primitive's consecutive samples in one line count once)") \
  X(Counter, depth_misses, "accesses", Sum, "Depth/stencil accesses that missed (line fetched from memory)") \
  X(Counter, color_accesses, "accesses", Sum, "Colour cache line accesses: writes, blend and framebuffer-fetch reads") \
  X(Counter, color_read_misses, "accesses", Sum, "Colour reads (blending, framebuffer fetch) that missed (line fetched from memory)") \
  X(Counter, fill_bytes, "bytes", Sum, "Bytes the ROP caches fetched from memory on misses") \
  X(Counter, writeback_bytes, "bytes", Sum, "Dirty lines the ROP caches wrote to memory (evictions and the flush at the end of each pass)") \
  X(Counter, accessed_bytes, "bytes", Sum, "Bytes the ISP and TSP read and wrote in the ROP caches (their SRAM energy)") \
  X(Counter, clear_bytes, "bytes", Sum, "Bytes written to memory by clears (imr.clear=write) and fast-clear eliminates of lines never touched (imr.clear=fast)") \
  X(Counter, fast_cleared_fills, "accesses", Sum, "Misses on fast-cleared lines: installed with the clear value, nothing fetched")
/// Statistics of the render output unit.
struct RopStats {
  TBDR_STATS(TBDR_ROP_STATS)
};

/// The render output unit of gpu.mode=imr: depth and colour caches in front of the framebuffer.
class RenderOutputUnit {
 public:
  /// Pixels per side of a framebuffer block (a 4x4 block of 32-bit pixels is one 64-byte line).
  static constexpr int kBlockPixels = 4;

  RenderOutputUnit(const HwConfig& hw, int width, int height);

  /// Binds the pass whose draws follow: its depth attachment and colour targets, at their images'
  /// places in the framebuffer address space (an image keeps its place across passes); its
  /// statistics go to `stats`.
  void bind_pass(const PassDesc& pass, RopStats& stats);
  /// Places the images `pass` binds and clears, in the order bind_pass and its clears would,
  /// without binding it. Called for every pass of a frame before the first runs, it fixes the
  /// framebuffer's size (framebuffer_bytes) before any command is timed.
  void place_pass(const PassDesc& pass);
  /// One depth/stencil test (write: the sample's depth or stencil changes) of sample `s` at (x, y).
  void depth(int x, int y, int s, bool write);
  /// A shader's colour output to the pass's colour target `target` at the samples `mask` of
  /// (x, y): read first when it blends or fetches the framebuffer.
  void color(std::size_t target, int x, int y, std::uint32_t mask, bool read);
  /// A clear of attachment `a` at the start of the bound pass (imr.clear): fast, its lines are
  /// marked cleared (nothing moves now); write, every line is written to memory now (in the colour
  /// stream, before the pass's draws).
  void clear(const Attachment& a);
  /// Next primitive: accesses of different primitives are never merged.
  void next_primitive() { last_depth_ = last_color_ = kNone; }
  /// Writes every dirty line back (the end of a pass): appended to the colour stream.
  void flush();
  /// The misses and write-backs since the last call, in order: those of depth tests (made while
  /// the ISP works) and those of colour writes (made while the TSP's results leave).
  std::vector<FramebufferAccess> take_depth_accesses() { return std::move(depth_out_); }
  std::vector<FramebufferAccess> take_color_accesses() { return std::move(color_out_); }
  /// Bytes of the framebuffer address space the bound images use so far.
  std::uint64_t framebuffer_bytes() const { return next_base_; }

 private:
  static constexpr std::uint64_t kNone = UINT64_MAX;
  /// The place of one image: base address and bytes per sample.
  struct Image {
    std::uint64_t base = 0;
    std::uint32_t bytes_per_sample = 0;
    std::uint32_t samples = 1;
    DramClass cls = DramClass::Color;
    std::uint64_t lines = 0;           ///< cache lines the image spans
    std::vector<bool> cleared;         ///< per line: fast-cleared and not touched since
    bool stored = false;               ///< the bound pass stores it (a fast-clear eliminate writes untouched cleared lines)
  };
  Image& place(const Attachment& a);
  std::uint64_t address(const Image& img, int x, int y, int s) const;
  /// One access of the line holding `addr`; consecutive accesses of one line in the same
  /// direction merge (`last`: the previous access, line x 2 + write).
  void access(Cache& cache, Image& img, std::uint64_t addr, bool write, std::vector<FramebufferAccess>& out,
              std::uint64_t& last);

  int width_ = 0;
  int blocks_x_ = 0;
  int blocks_y_ = 0;
  std::uint64_t depth_bytes_per_sample_ = 0;
  Cache depth_cache_;
  Cache color_cache_;
  std::map<std::string, Image> images_;   ///< by attachment name
  bool fast_clear_ = true;                ///< imr.clear = fast
  std::uint64_t color_line_bytes_ = 0, depth_line_bytes_ = 0;
  std::uint64_t next_base_ = 0;
  Image* depth_ = nullptr;                ///< the bound pass's depth image
  std::vector<Image*> targets_;           ///< the bound pass's colour targets, in output order
  std::uint64_t last_depth_ = kNone, last_color_ = kNone;
  std::vector<FramebufferAccess> depth_out_, color_out_;
  RopStats* stats_ = nullptr;             ///< the bound pass's statistics
};

}  // namespace tbdr
