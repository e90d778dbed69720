#pragma once
// Content hashing for results provenance: configs, traces and scene files are identified by a
// 64-bit FNV-1a hash printed as 16 hex digits.
#include <cstdint>
#include <cstdio>
#include <string>
#include <string_view>

namespace tbdr {

/// Incremental 64-bit FNV-1a hash: feed bytes, read hex(). Not cryptographic; it identifies inputs.
class Fnv1a64 {
 public:
  void update(const void* data, std::size_t size) {
    const auto* p = static_cast<const unsigned char*>(data);
    for (std::size_t i = 0; i < size; ++i) {
      state_ ^= p[i];
      state_ *= 0x100000001b3ULL;
    }
  }
  void update(std::string_view s) { update(s.data(), s.size()); }
  std::uint64_t value() const { return state_; }
  std::string hex() const {
    char buf[17];
    std::snprintf(buf, sizeof buf, "%016llx", static_cast<unsigned long long>(state_));
    return buf;
  }

 private:
  std::uint64_t state_ = 0xcbf29ce484222325ULL;
};

/// Hash of a whole string, as 16 hex digits.
inline std::string fnv1a_hex(std::string_view s) {
  Fnv1a64 h;
  h.update(s);
  return h.hex();
}

/// Hash of a file's bytes, as 16 hex digits; throws InputError naming the file when unreadable.
std::string hash_file_hex(const std::string& path);

}  // namespace tbdr
