#pragma once
// Per-run files for other tools, written from what the results database holds about a run (the
// same rows `report` and the views read, so the files and the database cannot disagree):
//  - a statistics dump: text in the layout of gem5's stats.txt ("name value # description (unit)"
//    between Begin/End banners), or JSON with each figure's value, unit and description when the
//    file name ends in .json;
//  - a timeline in the Chrome trace-event JSON format (opened by Perfetto, ui.perfetto.dev, and
//    chrome://tracing): per pass or dispatch its binning and its tile or compute work, from the
//    timing model's start / binning end / end cycles, each unit's busy, stalled and idle share, and
//    per unit and pass the intervals the unit was busy (TimingResult: the run just simulated, whose
//    busy cycles per unit add up to what the database holds).
#include <cstdint>
#include <string>

#include "models/timing_model.hpp"

namespace tbdr {

class ResultsDb;

/// InputError naming `path` (and `option`) unless a file can be written there: its folder exists
/// and is writable, and it is not a folder. Checked before a run, so a bad path costs no run.
void check_output_file(const std::string& option, const std::string& path);

/// Writes the statistics of run `run_id`: every stored statistic (scope/name, value, unit,
/// description), the derived figures of v_metric (views.sql) and the run's identity. JSON when
/// `path` ends in .json, gem5-style text otherwise. InputError when the run is absent or the file
/// cannot be written.
void write_stats_file(const ResultsDb& db, std::int64_t run_id, const std::string& path);

/// Writes the timeline of run `run_id` as Chrome trace-event JSON (timestamps in microseconds of
/// simulated time), with the units' busy intervals per pass from `timing` (that run's timing
/// result). InputError when the run has no timing figures or the file cannot be written.
void write_timeline_file(const ResultsDb& db, std::int64_t run_id, const TimingResult& timing, const std::string& path);

}  // namespace tbdr
