#pragma once
// The progress display of a sweep: a bar redrawn in place on a terminal, one line per finished
// point otherwise (logs, Slurm output), or nothing.
#include <chrono>
#include <cstddef>
#include <iosfwd>
#include <string>

namespace tbdr {

struct SweepPoint;

/// How progress is shown.
enum class SweepProgress { Bar, Lines, None };

/// Shows a sweep's progress: a redrawn bar on a terminal, one line per finished point otherwise.
class SweepProgressDisplay {
 public:
  /// `total` points in the slice, of which `skipped` were already in the database.
  SweepProgressDisplay(SweepProgress mode, std::ostream& out, std::size_t total, std::size_t skipped);

  /// A point finished (`error`: why it failed).
  void finished(const SweepPoint& p, bool ok, double seconds, const std::string& error);
  /// A point was found done meanwhile (another sweep on the same database ran it).
  void skipped();
  /// A line of its own (stopping on Ctrl-C), above the bar.
  void message(const std::string& text);
  /// The number of points running, shown on the bar.
  void set_running(std::size_t running);
  /// Redraws the bar at most ten times a second (or at once when forced).
  void draw(bool force);
  /// Leaves the bar drawn in full with a newline after it.
  void end();

 private:
  double elapsed() const;
  std::string rate_text() const;
  std::string eta_text() const;
  void clear_bar();

  SweepProgress mode_;
  std::ostream& out_;
  std::size_t total_, done_, ran_ = 0, failed_ = 0, running_ = 0;
  std::chrono::steady_clock::time_point start_, last_draw_{};
  bool drawn_ = false;
};

}  // namespace tbdr
