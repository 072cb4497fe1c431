// Minimal text output for firmware without a C library: decimal and hex
// formatting into a caller buffer, then board::log.
#pragma once
#include <cstddef>
#include <cstdint>

namespace vds::fw {

// Appends to a fixed line buffer; silently stops at its end.
class Line {
 public:
  Line& str(const char* s) {
    while (*s && n_ + 1 < sizeof buf_) buf_[n_++] = *s++;
    buf_[n_] = 0;
    return *this;
  }
  Line& dec(uint64_t v) {
    char tmp[24];
    int k = 0;
    do {
      tmp[k++] = static_cast<char>('0' + v % 10);
      v /= 10;
    } while (v);
    while (k) put(tmp[--k]);
    return *this;
  }
  Line& hex32(uint32_t v) {
    for (int s = 28; s >= 0; s -= 4) put("0123456789abcdef"[(v >> s) & 0xF]);
    return *this;
  }
  const char* c_str() const { return buf_; }

 private:
  void put(char c) {
    if (n_ + 1 < sizeof buf_) buf_[n_++] = c;
    buf_[n_] = 0;
  }
  char buf_[160] = {};
  size_t n_ = 0;
};

}  // namespace vds::fw
