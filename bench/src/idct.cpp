// Benchmark driver for the client IDCT (vds/idct.h): runs one entry point over
// fixed pseudo-random, realistically quantised 8x8 blocks. bench/run_idct.sh
// counts instructions per call with callgrind (--toggle-collect on the entry
// point); without valgrind the program reports wall-clock time per block.
//
//   bench_idct                   all cases, timing table
//   bench_idct CASE [N]          one case over N blocks (for callgrind); prints
//                                an FNV-1a checksum of everything it wrote
//   bench_idct --dump SET N FILE the first N blocks of a set (dense, sparse,
//                                dc) as little-endian int16, for the Cortex-M4
//                                run of the same cases (bench/m4/idct_qemu.cpp)
//   bench_idct --list            the case names
#include <algorithm>
#include <array>
#include <chrono>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <string>
#include <vector>

#include "vds/enc/dct.h"
#include "vds/idct.h"

namespace {

using Block = std::array<int16_t, 64>;

// JPEG luminance quantisation table (ITU-T T.81 Annex K.1), natural order.
constexpr int kLumaQuant[64] = {
    16, 11, 10, 16, 24,  40,  51,  61,  12, 12, 14, 19, 26,  58,  60,  55,
    14, 13, 16, 24, 40,  57,  69,  56,  14, 17, 22, 29, 51,  87,  80,  62,
    18, 22, 37, 56, 68,  109, 103, 77,  24, 35, 55, 64, 81,  104, 113, 92,
    49, 64, 78, 87, 103, 121, 120, 101, 72, 92, 95, 98, 112, 100, 103, 99};

struct Rng {  // xorshift32: fixed sequence on every host
  uint32_t s = 0x2545f491u;
  uint32_t next() {
    s ^= s << 13;
    s ^= s >> 17;
    s ^= s << 5;
    return s;
  }
  int range(int lo, int hi) { return lo + static_cast<int>(next() % static_cast<uint32_t>(hi - lo + 1)); }
};

// Forward DCT, quantise with the luma table times `scale_pct` percent, then
// dequantise: the coefficients a decoder hands to the IDCT.
Block quantised(const int16_t pix[64], int scale_pct) {
  int16_t f[64];
  vds::enc::fdct8x8(pix, f);
  Block b{};
  for (int i = 0; i < 64; ++i) {
    const int q = std::max(1, (kLumaQuant[i] * scale_pct + 50) / 100);
    const int level = (f[i] >= 0 ? f[i] + q / 2 : f[i] - q / 2) / q;
    b[i] = static_cast<int16_t>(std::clamp(level * q, vds::kIdctCoefMin, vds::kIdctCoefMax));
  }
  return b;
}

int nonzero_ac(const Block& b) {
  int n = 0;
  for (int i = 1; i < 64; ++i) n += b[i] != 0;
  return n;
}

// dense: textured intra blocks (gradient + edge + noise, level-shifted) at
//        about JPEG quality 90.
// sparse: smooth inter residuals at about quality 50, keeping blocks with
//        1..8 AC coefficients (DC-only ones go to the dc set).
// dc:    DC only.
std::vector<Block> make_blocks(const std::string& kind, int n) {
  Rng rng;
  std::vector<Block> out;
  out.reserve(static_cast<size_t>(n));
  while (static_cast<int>(out.size()) < n) {
    int16_t pix[64];
    if (kind == "dc") {
      Block b{};
      b[0] = static_cast<int16_t>(rng.range(-1024, 1023));
      out.push_back(b);
      continue;
    }
    if (kind == "dense") {
      const int gx = rng.range(-12, 12), gy = rng.range(-12, 12), base = rng.range(-100, 100);
      const int edge = rng.range(0, 15), step = rng.range(-80, 80), noise = rng.range(4, 30);
      for (int y = 0; y < 8; ++y)
        for (int x = 0; x < 8; ++x) {
          int v = base + gx * x + gy * y + (x + (edge & 7) > 7 + (edge >> 3) * y / 4 ? step : 0);
          v += rng.range(-noise, noise);
          pix[8 * y + x] = static_cast<int16_t>(std::clamp(v, -128, 127));
        }
      out.push_back(quantised(pix, 20));
    } else {
      const int gx = rng.range(-4, 4), gy = rng.range(-4, 4), base = rng.range(-20, 20);
      for (int y = 0; y < 8; ++y)
        for (int x = 0; x < 8; ++x) pix[8 * y + x] = static_cast<int16_t>(base + gx * (x - 3) + gy * (y - 3) + rng.range(-3, 3));
      const Block b = quantised(pix, 100);
      const int ac = nonzero_ac(b);
      if (ac >= 1 && ac <= 8) out.push_back(b);
    }
  }
  return out;
}

// The destination plane for put/add (256 x 64 pixels, starts at 128).
constexpr ptrdiff_t kStride = 256;
constexpr int kPlaneRows = 64;

struct Case {
  const char* name;
  const char* set;   // which block set
  const char* what;  // entry point exercised
};

constexpr Case kCases[] = {
    {"store-dense", "dense", "idct8x8"},       {"store-sparse", "sparse", "idct8x8"},
    {"store-dc", "dc", "idct8x8"},             {"put-dense", "dense", "idct8x8_put"},
    {"put-sparse", "sparse", "idct8x8_put"},   {"put-dc", "dc", "idct8x8_put"},
    {"add-dense", "dense", "idct8x8_add"},     {"add-sparse", "sparse", "idct8x8_add"},
    {"put_dc-dc", "dc", "idct8x8_put_dc"},     {"add_dc-dc", "dc", "idct8x8_add_dc"},
};

enum class Entry { store, put, add, put_dc, add_dc };

Entry entry_of(const Case& c) {
  const std::string w = c.what;
  if (w == "idct8x8") return Entry::store;
  if (w == "idct8x8_put") return Entry::put;
  if (w == "idct8x8_add") return Entry::add;
  if (w == "idct8x8_put_dc") return Entry::put_dc;
  return Entry::add_dc;
}

// Where block i lands: successive 8x8 positions of a 256-pixel-wide plane,
// as in a decoder writing a frame band. bench/m4/idct_qemu.cpp uses the same.
uint8_t* block_dst(std::vector<uint8_t>& plane, size_t i) {
  const size_t per_band = kStride / 8;
  return plane.data() + (i % per_band) * 8 + ((i / per_band) % (kPlaneRows / 8)) * 8 * kStride;
}

// Kept out of line so a profiler sees one call of the entry point per block.
// idct8x8 writes each block's output to its own slot of `out`.
template <Entry kEntry>
__attribute__((noinline)) void run_blocks(const std::vector<Block>& blocks, std::vector<uint8_t>& plane,
                                          std::vector<int16_t>& out) {
  for (size_t i = 0; i < blocks.size(); ++i) {
    uint8_t* dst = block_dst(plane, i);
    const int16_t* coef = blocks[i].data();
    if constexpr (kEntry == Entry::store) {
      vds::idct8x8(coef, out.data() + 64 * i);
    } else if constexpr (kEntry == Entry::put) {
      vds::idct8x8_put(coef, dst, kStride);
    } else if constexpr (kEntry == Entry::add) {
      vds::idct8x8_add(coef, dst, kStride);
    } else if constexpr (kEntry == Entry::put_dc) {
      vds::idct8x8_put_dc(coef[0], dst, kStride);
    } else {
      vds::idct8x8_add_dc(coef[0], dst, kStride);
    }
  }
}

void run_case(const Case& c, const std::vector<Block>& blocks, std::vector<uint8_t>& plane,
              std::vector<int16_t>& out) {
  switch (entry_of(c)) {
    case Entry::store: return run_blocks<Entry::store>(blocks, plane, out);
    case Entry::put: return run_blocks<Entry::put>(blocks, plane, out);
    case Entry::add: return run_blocks<Entry::add>(blocks, plane, out);
    case Entry::put_dc: return run_blocks<Entry::put_dc>(blocks, plane, out);
    case Entry::add_dc: return run_blocks<Entry::add_dc>(blocks, plane, out);
  }
}

// FNV-1a over the bytes written: the outputs (idct8x8) or the plane.
uint32_t checksum(const Case& c, const std::vector<uint8_t>& plane, const std::vector<int16_t>& out) {
  uint32_t h = 2166136261u;
  auto byte = [&h](uint8_t b) { h = (h ^ b) * 16777619u; };
  if (entry_of(c) == Entry::store) {
    for (int16_t v : out) {
      byte(static_cast<uint8_t>(static_cast<uint16_t>(v) & 0xff));
      byte(static_cast<uint8_t>(static_cast<uint16_t>(v) >> 8));
    }
  } else {
    for (uint8_t p : plane) byte(p);
  }
  return h;
}

const Case* find_case(const char* name) {
  for (const Case& c : kCases)
    if (std::strcmp(c.name, name) == 0) return &c;
  return nullptr;
}

double mean_nonzero(const std::vector<Block>& blocks) {
  long n = 0;
  for (const Block& b : blocks) n += nonzero_ac(b) + (b[0] != 0);
  return static_cast<double>(n) / static_cast<double>(blocks.size());
}

}  // namespace

int main(int argc, char** argv) {
  if (argc >= 2 && std::strcmp(argv[1], "--list") == 0) {
    for (const Case& c : kCases) std::printf("%s %s %s\n", c.name, c.what, c.set);
    return 0;
  }
  if (argc >= 2 && std::strcmp(argv[1], "--dump") == 0) {
    const int n = argc == 5 ? std::atoi(argv[3]) : 0;
    const std::string set = argc == 5 ? argv[2] : "";
    if (n <= 0 || (set != "dense" && set != "sparse" && set != "dc")) {
      std::fprintf(stderr, "usage: bench_idct --dump dense|sparse|dc N FILE\n");
      return 2;
    }
    std::FILE* f = std::fopen(argv[4], "wb");
    if (!f) {
      std::perror(argv[4]);
      return 1;
    }
    for (const Block& b : make_blocks(set, n))
      for (int16_t v : b) {
        const uint16_t u = static_cast<uint16_t>(v);
        const uint8_t le[2] = {static_cast<uint8_t>(u & 0xff), static_cast<uint8_t>(u >> 8)};
        std::fwrite(le, 1, 2, f);
      }
    return std::fclose(f) == 0 ? 0 : 1;
  }
  if (argc >= 2) {
    const Case* c = find_case(argv[1]);
    if (!c) {
      std::fprintf(stderr, "unknown case '%s' (see --list)\n", argv[1]);
      return 2;
    }
    const int n = argc >= 3 ? std::atoi(argv[2]) : 10000;
    if (n <= 0) {
      std::fprintf(stderr, "N must be positive\n");
      return 2;
    }
    const auto blocks = make_blocks(c->set, n);
    std::vector<uint8_t> plane(static_cast<size_t>(kStride * kPlaneRows), 128);
    std::vector<int16_t> out(blocks.size() * 64);
    run_case(*c, blocks, plane, out);
    std::printf("case=%s entry=%s blocks=%d nonzero_per_block=%.2f checksum=0x%08x\n", c->name, c->what, n,
                mean_nonzero(blocks), checksum(*c, plane, out));
    return 0;
  }
  const int n = 20000, reps = 20;
  std::printf("%-14s %-16s %10s %12s\n", "case", "entry", "nonzero", "ns/block");
  for (const Case& c : kCases) {
    const auto blocks = make_blocks(c.set, n);
    std::vector<uint8_t> plane(static_cast<size_t>(kStride * kPlaneRows), 128);
    std::vector<int16_t> out(blocks.size() * 64);
    const auto t0 = std::chrono::steady_clock::now();
    for (int r = 0; r < reps; ++r) run_case(c, blocks, plane, out);
    const auto t1 = std::chrono::steady_clock::now();
    const double ns = std::chrono::duration<double, std::nano>(t1 - t0).count() / (double{n} * reps);
    std::printf("%-14s %-16s %10.2f %12.2f\n", c.name, c.what, mean_nonzero(blocks), ns);
  }
  return 0;
}
