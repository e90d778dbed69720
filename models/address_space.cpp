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
  if (name.empty()) throw std::invalid_argument("address space: a region needs a name");
  if (by_name_.count(name) != 0) throw std::invalid_argument("address space: region '" + name + "' already allocated");
  if (align_bytes != 0 && !is_pow2(align_bytes)) {
    throw std::invalid_argument("address space: alignment of '" + name + "' must be a power of two");
  }
  const std::uint64_t align = std::max(page_bytes_, align_bytes);
  AddressRegion r;
  r.name = std::move(name);
  r.base = round_up(top_, align);
  r.size_bytes = size_bytes;
  r.reserved_bytes = round_up(std::max<std::uint64_t>(size_bytes, 1), page_bytes_);
  r.cls = cls;
  if (r.base > UINT64_MAX - r.reserved_bytes) throw std::overflow_error("address space: allocation overflows 64 bits");
  top_ = r.base + r.reserved_bytes;
  reserved_ += r.reserved_bytes;
  by_name_.emplace(r.name, regions_.size());
  regions_.push_back(std::move(r));
  return regions_.back().base;
}

const AddressRegion* AddressSpace::find(std::string_view name) const {
  const auto it = by_name_.find(std::string(name));
  return it == by_name_.end() ? nullptr : &regions_[it->second];
}

const AddressRegion& AddressSpace::region(std::string_view name) const {
  const AddressRegion* r = find(name);
  if (r == nullptr) throw std::out_of_range("address space: no region named '" + std::string(name) + "'");
  return *r;
}

const AddressRegion* AddressSpace::region_at(std::uint64_t addr) const {
  // Regions are allocated at increasing addresses: the last one whose base <= addr is the candidate.
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

void AddressSpace::clear() {
  regions_.clear();
  by_name_.clear();
  top_ = base_;
  reserved_ = 0;
}

}  // namespace tbdr
