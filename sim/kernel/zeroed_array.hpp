#pragma once
// An array of trivially copyable T that starts all zero bytes and takes memory only for the pages
// used: large arrays are anonymous private mappings (the kernel maps a page when it is first
// touched), small ones an ordinary zeroed allocation. Pages only read may share the kernel's zero
// page, but not everywhere (some sandboxes map a page on a read too), so a user reads only what it
// has written. A cache of 256 MiB in 16-byte lines has 16 M slots; a frame touches a fraction of
// them, so its tag arrays cost the lines touched, not the capacity (docs/limits.md).
#include <sys/mman.h>

#include <cstddef>
#include <cstring>
#include <new>
#include <type_traits>
#include <utility>

namespace tbdr {

/// A fixed-size array of T, zero-initialised, whose untouched pages take no memory.
template <class T>
class ZeroedArray {
  static_assert(std::is_trivially_copyable_v<T>, "the array is zero bytes, not constructed");

 public:
  /// Below this size (bytes) the array is an ordinary allocation: a mapping costs a system call
  /// and a page fault per page, which small arrays (a default 16 KiB cache's 2 KiB of tags) would
  /// pay for no memory saved.
  static constexpr std::size_t kMappedFromBytes = std::size_t{1} << 20;

  ZeroedArray() = default;
  explicit ZeroedArray(std::size_t n) : size_(n), bytes_(n * sizeof(T)) {
    if (bytes_ == 0) return;
    if (bytes_ >= kMappedFromBytes) {
      void* p = mmap(nullptr, bytes_, PROT_READ | PROT_WRITE, MAP_PRIVATE | MAP_ANONYMOUS | MAP_NORESERVE, -1, 0);
      if (p == MAP_FAILED) throw std::bad_alloc();
      data_ = static_cast<T*>(p);
      mapped_ = true;
    } else {
      data_ = static_cast<T*>(::operator new(bytes_));
      std::memset(static_cast<void*>(data_), 0, bytes_);
    }
  }
  ~ZeroedArray() { release(); }
  ZeroedArray(ZeroedArray&& o) noexcept { swap(o); }
  ZeroedArray& operator=(ZeroedArray&& o) noexcept {
    if (this != &o) {
      release();
      swap(o);
    }
    return *this;
  }
  ZeroedArray(const ZeroedArray&) = delete;
  ZeroedArray& operator=(const ZeroedArray&) = delete;

  T& operator[](std::size_t i) { return data_[i]; }
  const T& operator[](std::size_t i) const { return data_[i]; }
  T* data() { return data_; }
  const T* data() const { return data_; }
  std::size_t size() const { return size_; }

  /// Every element back to zero bytes; a mapping gives its pages back (MADV_DONTNEED: the next
  /// read of an anonymous private page is zero), so clearing does not touch the untouched pages.
  void clear() {
    if (bytes_ == 0) return;
    if (!mapped_ || madvise(data_, bytes_, MADV_DONTNEED) != 0) std::memset(static_cast<void*>(data_), 0, bytes_);
  }

 private:
  void release() {
    if (!data_) return;
    if (mapped_) {
      munmap(data_, bytes_);
    } else {
      ::operator delete(data_);
    }
    data_ = nullptr;
  }
  void swap(ZeroedArray& o) noexcept {
    std::swap(data_, o.data_);
    std::swap(size_, o.size_);
    std::swap(bytes_, o.bytes_);
    std::swap(mapped_, o.mapped_);
  }

  T* data_ = nullptr;
  std::size_t size_ = 0;
  std::size_t bytes_ = 0;
  bool mapped_ = false;
};

}  // namespace tbdr
