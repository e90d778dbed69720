#include "models/address_space.hpp"

#include <algorithm>
#include <stdexcept>

#include "kernel/bits.hpp"

namespace tbdr {

namespace {

std::uint64_t round_up(std::uint64_t v, std::uint64_t granule) {
  if (v > UINT64_MAX - (granule - 1)) throw std::overflow_error("address space: allocation overflows 64 bits");
  return (v + granule - 1) & ~(granule - 1);
}

}  // namespace

AddressSpace::AddressSpace(std::uint64_t page_bytes, std::uint64_t base) : page_bytes_(page_bytes) {
  if (!is_pow2(page_bytes)) throw std::invalid_argument("address space: page size must be a power of two");
  base_ = round_up(base, page_bytes_);
  top_ = base_;
}

std::uint64_t AddressSpace::allocate(std::string name, std::uint64_t size_bytes, DramClass cls,
                                     std::uint64_t align_bytes) {
  return place(std::move(name), size_bytes, cls, align_bytes, top_, kHighBase);
}

std::uint64_t AddressSpace::allocate_high(std::string name, std::uint64_t size_bytes, DramClass cls) {
  return place(std::move(name), size_bytes, cls, 0, high_top_, UINT64_MAX);
}

std::uint64_t AddressSpace::reuse_or_allocate(const std::string& name, std::uint64_t size_bytes, DramClass cls, bool high) {
  for (int n = 1;; ++n) {
    const std::string candidate = n == 1 ? name : name + "#" + std::to_string(n);
    const AddressRegion* r = find(candidate);
    if (r == nullptr) return high ? allocate_high(candidate, size_bytes, cls) : allocate(candidate, size_bytes, cls);
    if (r->cls == cls && r->reserved_bytes >= size_bytes && (r->base >= kHighBase) == high) return r->base;
  }
}

std::uint64_t AddressSpace::place(std::string name, std::uint64_t size_bytes, DramClass cls, std::uint64_t align_bytes,
                                  std::uint64_t& cursor, std::uint64_t limit) {
  if (name.empty()) throw std::invalid_argument("address space: a region needs a name");
  if (by_name_.count(name) != 0) throw std::invalid_argument("address space: region '" + name + "' already allocated");
  if (align_bytes != 0 && !is_pow2(align_bytes)) {
    throw std::invalid_argument("address space: alignment of '" + name + "' must be a power of two");
  }
  const std::uint64_t align = std::max(page_bytes_, align_bytes);
  AddressRegion r;
  r.name = std::move(name);
  r.base = round_up(cursor, align);
  r.size_bytes = size_bytes;
  r.reserved_bytes = round_up(std::max<std::uint64_t>(size_bytes, 1), page_bytes_);
  r.cls = cls;
  if (r.base > limit - r.reserved_bytes || r.base > UINT64_MAX - r.reserved_bytes) {
    throw std::overflow_error("address space: allocation of '" + r.name + "' overflows its range");
  }
  cursor = r.base + r.reserved_bytes;
  reserved_ += r.reserved_bytes;
  const std::uint64_t base = r.base;
  by_name_.emplace(r.name, base);
  // In address order: a low region goes before the high range's.
  const auto at = std::upper_bound(regions_.begin(), regions_.end(), base,
                                   [](std::uint64_t a, const AddressRegion& x) { return a < x.base; });
  regions_.insert(at, std::move(r));
  return base;
}

const AddressRegion* AddressSpace::find(std::string_view name) const {
  const auto it = by_name_.find(std::string(name));
  return it == by_name_.end() ? nullptr : region_at(it->second);
}

const AddressRegion& AddressSpace::region(std::string_view name) const {
  const AddressRegion* r = find(name);
  if (r == nullptr) throw std::out_of_range("address space: no region named '" + std::string(name) + "'");
  return *r;
}

const AddressRegion* AddressSpace::region_at(std::uint64_t addr) const {
  // Regions are kept in address order: the last one whose base <= addr is the candidate.
  auto it = std::upper_bound(regions_.begin(), regions_.end(), addr,
                             [](std::uint64_t a, const AddressRegion& r) { return a < r.base; });
  if (it == regions_.begin()) return nullptr;
  --it;
  return it->contains(addr) ? &*it : nullptr;
}

DramClass AddressSpace::class_at(std::uint64_t addr) const {
  const AddressRegion* r = region_at(addr);
  return r == nullptr ? DramClass::Other : r->cls;
}

void AddressSpace::adopt(const std::vector<AddressRegion>& regions) {
  if (!regions_.empty()) throw std::logic_error("address space: adopt needs an empty space");
  for (const AddressRegion& r : regions) {
    if (by_name_.count(r.name) != 0) throw std::invalid_argument("address space: region '" + r.name + "' adopted twice");
    std::uint64_t& cursor = r.base >= kHighBase ? high_top_ : top_;
    cursor = std::max(cursor, r.base + r.reserved_bytes);
    reserved_ += r.reserved_bytes;
    by_name_.emplace(r.name, r.base);
    const auto at = std::upper_bound(regions_.begin(), regions_.end(), r.base,
                                     [](std::uint64_t a, const AddressRegion& x) { return a < x.base; });
    regions_.insert(at, r);
  }
}

void AddressSpace::clear() {
  regions_.clear();
  by_name_.clear();
  top_ = base_;
  high_top_ = kHighBase;
  reserved_ = 0;
}

}  // namespace tbdr
