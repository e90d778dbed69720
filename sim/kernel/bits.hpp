#pragma once
// Power-of-two helpers for the address arithmetic of caches, DRAM mapping and the address space,
// and the bit count of coverage and block masks: written once here, so every unit tests, shifts
// and counts the same way.
#include <bit>
#include <cstdint>

namespace tbdr {

/// True when v is a power of two (0 is not).
constexpr bool is_pow2(std::uint64_t v) { return std::has_single_bit(v); }

/// log2 of a power of two (the shift that multiplies by v). Precondition: is_pow2(v).
constexpr unsigned log2_exact(std::uint64_t v) { return static_cast<unsigned>(std::countr_zero(v)); }

/// Set bits of x, by the SWAR (SIMD within a register) sum of bit fields: std::popcount is a call
/// to libgcc's table-driven __popcountdi2 when the target has no popcnt instruction (x86-64
/// without -mpopcnt); this is a few register operations on any target (compilers that know the
/// idiom turn it into popcnt where the target has one).
constexpr std::uint32_t bit_count(std::uint64_t x) {
  x -= (x >> 1) & 0x5555555555555555ull;                                 // 2-bit fields: 0..2
  x = (x & 0x3333333333333333ull) + ((x >> 2) & 0x3333333333333333ull);  // 4-bit fields: 0..4
  x = (x + (x >> 4)) & 0x0F0F0F0F0F0F0F0Full;                            // bytes: 0..8
  return static_cast<std::uint32_t>((x * 0x0101010101010101ull) >> 56);  // the sum of the bytes
}

}  // namespace tbdr
