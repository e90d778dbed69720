#pragma once
// Merging shard databases (the slices of a sweep run as a Slurm job array) into one results
// database, without duplicating runs that are already there.
#include <cstddef>
#include <string>
#include <vector>

namespace tbdr {

/// What merging one shard did.
struct MergeShardResult {
  std::string shard;
  std::size_t copied = 0;
  std::size_t duplicates = 0;
};

/// Merges shard databases into `out_path` (created if absent), one transaction per shard, with new
/// run ids. A finished run whose (config_hash, trace_hash) is already finished in the output is a
/// duplicate (repetitions are kept: a shard's k-th finished run of a point is copied when the
/// output holds fewer than k); failed runs are copied unless an identical row is already there.
/// Every shard and the output are checked first: InputError, with nothing written, when one is
/// missing, not a tbdrsim database, newer than this tbdrsim, or the output cannot take runs. A new
/// output is written under a temporary name and renamed into place when every shard is in, so a
/// merge that fails leaves no output file.
std::vector<MergeShardResult> merge_databases(const std::string& out_path, const std::vector<std::string>& shards);

}  // namespace tbdr
