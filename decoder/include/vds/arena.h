// vds client library: the bump allocator that carves a caller-owned
// workspace. Nothing in the client library allocates any other way.
#pragma once
#include <cstddef>
#include <cstdint>

namespace vds {

// A view of caller-owned memory handed out front to back. Allocation never
// fails silently: a null return means "workspace too small" and the caller
// turns it into Status::workspace_too_small.
class Arena {
 public:
  Arena() = default;
  Arena(void* base, size_t size) : base_(static_cast<uint8_t*>(base)), size_(base ? size : 0) {}

  // `bytes` bytes aligned to `align` (a power of two), or nullptr.
  void* alloc(size_t bytes, size_t align = alignof(uint32_t)) {
    const uintptr_t start = reinterpret_cast<uintptr_t>(base_) + used_;
    const size_t pad = static_cast<size_t>((align - (start & (align - 1))) & (align - 1));
    if (pad > size_ - used_ || bytes > size_ - used_ - pad) return nullptr;
    void* p = base_ + used_ + pad;
    used_ += pad + bytes;
    if (used_ > high_water_) high_water_ = used_;
    return p;
  }

  template <typename T>
  T* alloc_array(size_t count) {
    if (count > SIZE_MAX / sizeof(T)) return nullptr;
    return static_cast<T*>(alloc(count * sizeof(T), alignof(T)));
  }

  // Marks and rewinds let a decoder release per-frame scratch space.
  size_t mark() const { return used_; }
  void rewind(size_t mark) {
    if (mark <= used_) used_ = mark;
  }

  size_t used() const { return used_; }
  size_t remaining() const { return size_ - used_; }
  size_t capacity() const { return size_; }
  size_t high_water() const { return high_water_; }

 private:
  uint8_t* base_ = nullptr;
  size_t size_ = 0;
  size_t used_ = 0;
  size_t high_water_ = 0;
};

}  // namespace vds
