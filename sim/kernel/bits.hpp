#pragma once
// Power-of-two helpers for the address arithmetic of caches, DRAM mapping and the address space:
// written once here, so every unit tests and shifts the same way.
#include <bit>
#include <cstdint>

namespace tbdr {

/// True when v is a power of two (0 is not).
constexpr bool is_pow2(std::uint64_t v) { return std::has_single_bit(v); }

/// log2 of a power of two (the shift that multiplies by v). Precondition: is_pow2(v).
constexpr unsigned log2_exact(std::uint64_t v) { return static_cast<unsigned>(std::countr_zero(v)); }

}  // namespace tbdr
