#pragma once
// The run driver: one simulation from inputs to a database row. Reads the trace, loads the scene
// it references, replays the frame, writes the images, and stores the run (every resolved
// parameter, every statistic) in one transaction. Used by `run` and, later, by sweeps.
#include <cstdint>
#include <optional>
#include <iosfwd>
#include <string>

#include "models/hw_config.hpp"
#include "models/energy.hpp"
#include "models/timing_model.hpp"
#include "models/command_processor.hpp"
#include "analysis/report.hpp"
#include "analysis/results_db.hpp"
#include "app/stat_rows.hpp"
#include "app/run_stats.hpp"
#include "trace/trace.hpp"

namespace tbdr {

class DramObserver;  // models/dram_observer.hpp

/// What to simulate and where the results go.
struct RunRequest {
  ResolvedConfig config;
  std::string trace_path;
  std::string db_path;
  std::string images_dir;    ///< empty: no images
  std::string command_line;  ///< recorded in the runs table
  unsigned threads = 1;      ///< threads the frame's tiles render on (FrameOptions::threads); no figure depends on it
  bool summary_figures = true;  ///< read RunOutcome::derived back from the database (for print_run_summary)
  DramObserver* dram_observer = nullptr;  ///< sees the timing model's DRAM requests and commands (--memory-trace); not owned
  /// Sampled simulation of a sequence (--sample): the frames simulated to stand for it, each for a
  /// group of frames with similar signatures (app/sampled_run.hpp); 0: every frame is simulated.
  std::size_t sample_frames = 0;
  /// Frames simulated before each representative of a sampled run, from cold (--sample-warmup).
  std::size_t sample_warmup_frames = 1;
};

/// What a sampled run estimated (RunRequest::sample_frames > 0).
struct SampledOutcome {
  SamplingSummaryStats estimate;    ///< sampling/summary
  SequenceSummaryStats sequence;    ///< sequence/summary over the estimated frames
};

/// What a run produced.
struct RunOutcome {
  std::int64_t run_id = 0;
  std::string technique;
  std::string scene;
  double wall_seconds = 0;       ///< simulation only (trace read and scene load excluded)
  double load_seconds = 0;       ///< trace read and scene load
  double timing_seconds = 0;     ///< host time of the timing model
  double cpu_seconds = 0;        ///< host CPU time of the functional simulation
  double timing_cpu_seconds = 0; ///< host CPU time of the timing and energy models
  double timing_wait_seconds = 0; ///< host time the timing model waited for the functional run (WorkFeed::consumer_wait_seconds; 0 at one thread)
  double image_cpu_seconds = 0; ///< host CPU time of writing the images (write_frame_images on all its threads; 0 without)
  unsigned threads = 1;          ///< threads the simulation ran on
  FrameResult frame;              ///< its work without commands: those are released once timed
  TimingResult timing;
  EnergyBreakdown energy;
  /// A sequence (more than one frame): each frame's unit statistics (`frame` holds their sums) and
  /// its energy (sequence_frame_energy); empty for a single frame.
  SequenceFrames sequence;
  std::vector<StatRecord> stats;  ///< every row of the run but the host's (run_rows)
  std::vector<std::string> images_written;
  DerivedFigures derived;        ///< read back from the database (views.sql defines them) when RunRequest::summary_figures
  /// A sampled run's estimate; its `frame`, `timing` and `energy` are then empty: no frame/ rows
  /// are stored, as no run simulated the whole sequence.
  std::optional<SampledOutcome> sampled;
};

/// The configuration's label (ResolvedConfig::label) as the run parameter config.label (origin
/// "config"), which analysis/views.sql's v_config_label reads: one label per hardware and preset.
RunParam config_label_param(const std::string& label);

/// The trace's identity and technique options as run parameters (origin: the trace file and the
/// line of its header): technique.<option> for each option of the `technique` line, and
/// trace.camera for a named viewpoint. Dimensions of `report --by`/`--where` and of v_param.
std::vector<RunParam> trace_run_params(const Trace& trace, const std::string& trace_path);

/// Runs one simulation end to end. InputError on bad input (the database is checked first, before
/// the trace is read); nothing is written to the database unless the whole run succeeded.
RunOutcome run_one(const RunRequest& request);

/// Prints the figures a user looks at first.
void print_run_summary(const RunOutcome& outcome, std::ostream& out);

/// Writes the frame's images (final color, depth, triangle ids, heat maps) into `dir`, encoding
/// them on `threads` threads (the same files at any count), and returns their paths in a fixed
/// order. `cpu_seconds`, when given, receives the CPU seconds the encoding took on all threads.
std::vector<std::string> write_frame_images(const FrameResult& frame, const std::string& dir, unsigned threads = 1,
                                            double* cpu_seconds = nullptr);
/// Writes the heat map of cycles per tile (summed over the frame's passes).
std::string write_tile_cycles_image(const FrameResult& frame, const TimingResult& timing, const std::string& dir);

/// Runs the timing and energy models on a functional frame (its rows: run_rows, app/stat_rows.hpp).
void time_frame(const HwConfig& hw, const FrameResult& frame, TimingResult& timing, EnergyBreakdown& energy);
/// time_frame's second half: the energy of `frame` timed as `timing` (the timing model's result on
/// it, e.g. run beside the functional run on a WorkFeed).
void book_timing(const HwConfig& hw, const FrameResult& frame, const TimingResult& timing, EnergyBreakdown& energy);
/// Each frame's energy of a sequence: its unit statistics (`frames`, in order), the memory
/// system's energy between the end of the frame before and its end, and leakage over that
/// interval (TimingResult::frames); they add up to the sequence's. Empty for a single frame.
std::vector<EnergyBreakdown> sequence_frame_energy(const HwConfig& hw, const std::vector<FrameStats>& frames,
                                                   const TimingResult& timing);

}  // namespace tbdr
