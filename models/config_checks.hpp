#pragma once
// Constraints between hardware parameters that no per-key range can express (a cache's size against
// its ways and line size, DRAM rows against bursts, parameter-buffer pages against its capacity, ...).
// resolve_config checks them before any work, so a model's constructor never meets a configuration
// it refuses; a sweep checks every point's configuration when its file is read. docs/limits.md
// lists them.
#include <optional>
#include <string>
#include <vector>

#include "models/hw_config.hpp"

namespace tbdr {

/// One violated constraint: what is wrong (with the values) and the parameters it involves.
struct ConstraintViolation {
  std::string message;            ///< "cache.slc.line_bytes = 100 must be a power of two (...)"
  std::vector<std::string> keys;  ///< the parameters involved, e.g. {"cache.slc.line_bytes"}
};

/// The first constraint `hw` violates, in a fixed order (caches, DRAM, memory system, tiling,
/// geometry), or nothing.
std::optional<ConstraintViolation> first_constraint_violation(const HwConfig& hw);

/// Every parameter some constraint reads: a sweep checks only the combinations of the axes that
/// set one of them (or a config file), not every point.
const std::vector<std::string>& constrained_param_keys();

/// InputError when `hw` (resolved as `params`) violates a constraint: the message names every
/// parameter involved with its value and where it was set (a file:line, a --set argument, or the
/// default); the error's location is the first of those that is not the default.
void check_config_constraints(const HwConfig& hw, const ResolvedParams& params);

}  // namespace tbdr
