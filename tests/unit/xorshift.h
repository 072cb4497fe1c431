// The tests' small deterministic generator: xorshift32 (Marsaglia 2003).
#pragma once
#include <cstdint>

namespace vds::test {

struct Xorshift32 {
  uint32_t s = 0x9e3779b9u;  // any non-zero seed
  uint32_t next() {
    s ^= s << 13;
    s ^= s >> 17;
    s ^= s << 5;
    return s;
  }
};

}  // namespace vds::test
