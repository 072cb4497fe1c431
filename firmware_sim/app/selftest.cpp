// Firmware self-test: runs client-library kernels on fixed inputs and prints
// their checksums, so the same program on the host board and on the
// Cortex-M4 board must print identical "check" lines (bit-exactness across
// architectures); on the QEMU board it also prints instruction counts.
#include <cstdint>

#include "print.h"
#include "vds/board.h"
#include "vds/container.h"
#include "vds/crc32c.h"
#include "vds/idct.h"

namespace {

using vds::fw::Line;

// Deterministic pseudo-random numbers (the same on every board).
uint32_t g_rng = 0x12345678u;
uint32_t next_random() {
  g_rng = g_rng * 1664525u + 1013904223u;
  return g_rng;
}

// Sparse, realistic blocks: a DC, a few low-frequency AC coefficients.
void make_block(int16_t coef[64], int density) {
  for (int i = 0; i < 64; ++i) coef[i] = 0;
  coef[0] = static_cast<int16_t>(static_cast<int32_t>(next_random() >> 21) - 1024);
  for (int k = 0; k < density; ++k) {
    const uint32_t r = next_random();
    const int pos = static_cast<int>((r >> 8) % 64);
    coef[pos] = static_cast<int16_t>(static_cast<int32_t>((r >> 20) % 401) - 200);
  }
}

constexpr int kBlocks = 256;

void check_idct() {
  int16_t coef[64];
  int16_t out[64];
  uint8_t pixels[64];
  uint32_t crc_out = 0;
  uint32_t crc_put = 0;
  uint64_t spent = 0;
  for (int b = 0; b < kBlocks; ++b) {
    make_block(coef, 1 + b % 24);
    const uint64_t t0 = vds::board::instructions();
    vds::idct8x8(coef, out);
    spent += vds::board::instructions() - t0;
    vds::idct8x8_put(coef, pixels, 8);
    crc_out = vds::crc32c_update(crc_out, out, sizeof out);
    crc_put = vds::crc32c_update(crc_put, pixels, sizeof pixels);
  }
  vds::board::log(Line().str("check idct8x8 ").hex32(crc_out).str("\n").c_str());
  vds::board::log(Line().str("check idct8x8_put ").hex32(crc_put).str("\n").c_str());
  if (vds::board::instruction_resolution() != 0)
    vds::board::log(Line().str("count idct8x8 instructions_per_block ").dec(spent / kBlocks).str("\n").c_str());
}

void check_crc() {
  uint8_t data[1024];
  for (uint32_t i = 0; i < sizeof data; ++i) data[i] = static_cast<uint8_t>(next_random() >> 24);
  const uint64_t t0 = vds::board::instructions();
  const uint32_t c = vds::crc32c(data, sizeof data);
  const uint64_t spent = vds::board::instructions() - t0;
  vds::board::log(Line().str("check crc32c ").hex32(c).str(" ").hex32(vds::crc32c("123456789", 9)).str("\n").c_str());
  if (vds::board::instruction_resolution() != 0)
    vds::board::log(Line().str("count crc32c instructions_per_byte_x100 ").dec(spent * 100 / sizeof data).str("\n").c_str());
}

// A loop of known length checks the instruction counter itself: on the
// Cortex-M4 board each iteration is exactly two instructions (subs, bne).
void check_counter() {
  if (vds::board::instruction_resolution() == 0) return;
#if defined(__arm__)
  constexpr uint32_t kIterations = 100000;
  uint32_t n = kIterations;
  const uint64_t t0 = vds::board::instructions();
  asm volatile(
      "1: subs %0, %0, #1\n"
      "bne 1b\n"
      : "+r"(n)::"cc");
  const uint64_t spent = vds::board::instructions() - t0;
  vds::board::log(Line().str("count calibration_loop measured ").dec(spent).str(" expected ").dec(2ull * kIterations)
                      .str(" resolution ").dec(vds::board::instruction_resolution()).str("\n").c_str());
#endif
}

}  // namespace

// The firmware's entry point, called by each board's start-up code.
extern "C" int vds_app_main() {
  vds::board::init();
  vds::board::log("vds selftest\n");
  check_counter();
  check_crc();
  check_idct();
  vds::board::log(Line().str("info stack_high_water_bytes ").dec(vds::board::stack_high_water()).str("\n").c_str());
  return 0;
}
