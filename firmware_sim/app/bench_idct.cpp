// Cortex-M4 side of bench/run_idct.sh: runs the block sets that bench_idct
// dumps (idct_dense.bin, idct_sparse.bin, idct_dc.bin, read from the host in
// pieces) through every IDCT entry point, and prints instructions per call
// and a checksum of everything written, to compare with the x86-64 run.
#include <cstddef>
#include <cstdint>

#include "print.h"
#include "vds/board.h"
#include "vds/idct.h"

namespace {

using vds::fw::Line;

constexpr int kPieceBlocks = 256;  // blocks read from the host at a time
constexpr ptrdiff_t kStride = 256;  // the same plane geometry as bench/src/idct.cpp
constexpr int kPlaneRows = 64;

int16_t g_blocks[kPieceBlocks * 64];
int16_t g_out[64];
uint8_t g_plane[kStride * kPlaneRows];

enum class Entry { none, store, put, add, put_dc, add_dc };

[[gnu::noinline]] void null_entry(const int16_t*, uint8_t*, ptrdiff_t) { asm volatile(""); }

uint8_t* block_dst(uint32_t i) {
  const uint32_t per_band = kStride / 8;
  return g_plane + (i % per_band) * 8 + ((i / per_band) % (kPlaneRows / 8)) * 8 * kStride;
}

uint32_t fnv(uint32_t h, const uint8_t* p, size_t n) {
  for (size_t i = 0; i < n; ++i) h = (h ^ p[i]) * 16777619u;
  return h;
}

// Runs `n` blocks starting at global index `first`; returns instructions.
[[gnu::noinline]] uint64_t run_piece(Entry e, uint32_t first, int n, uint32_t* store_hash) {
  uint64_t spent = 0;
  for (int k = 0; k < n; ++k) {
    const int16_t* coef = g_blocks + 64 * k;
    uint8_t* dst = block_dst(first + static_cast<uint32_t>(k));
    const uint64_t t0 = vds::board::instructions();
    switch (e) {
      case Entry::none: null_entry(coef, dst, kStride); break;
      case Entry::store: vds::idct8x8(coef, g_out); break;
      case Entry::put: vds::idct8x8_put(coef, dst, kStride); break;
      case Entry::add: vds::idct8x8_add(coef, dst, kStride); break;
      case Entry::put_dc: vds::idct8x8_put_dc(coef[0], dst, kStride); break;
      case Entry::add_dc: vds::idct8x8_add_dc(coef[0], dst, kStride); break;
    }
    spent += vds::board::instructions() - t0;
    if (e == Entry::store) *store_hash = fnv(*store_hash, reinterpret_cast<const uint8_t*>(g_out), sizeof g_out);
  }
  return spent;
}

struct Case {
  const char* name;
  const char* file;
  Entry entry;
};

// Returns instructions over all blocks; false if the file cannot be read.
bool run_case(const Case& c, Entry e, uint32_t* blocks, uint64_t* spent, uint32_t* hash) {
  for (uint32_t i = 0; i < sizeof g_plane; ++i) g_plane[i] = 128;
  *blocks = 0;
  *spent = 0;
  *hash = 2166136261u;
  for (;;) {
    const int32_t got = vds::board::host_file_read(c.file, *blocks * 128u, reinterpret_cast<uint8_t*>(g_blocks),
                                                    sizeof g_blocks);
    if (got < 0) return false;
    const int n = got / 128;
    if (n == 0) break;
    *spent += run_piece(e, *blocks, n, hash);
    *blocks += static_cast<uint32_t>(n);
  }
  if (e != Entry::store) *hash = fnv(*hash, g_plane, sizeof g_plane);
  return *blocks > 0;
}

}  // namespace

extern "C" int vds_app_main() {
  vds::board::init();
  if (vds::board::instruction_resolution() == 0) {
    vds::board::log("m4 error: this board has no instruction counter\n");
    return 1;
  }
  static const Case cases[] = {
      {"store-dense", "idct_dense.bin", Entry::store}, {"store-sparse", "idct_sparse.bin", Entry::store},
      {"store-dc", "idct_dc.bin", Entry::store},       {"put-dense", "idct_dense.bin", Entry::put},
      {"put-sparse", "idct_sparse.bin", Entry::put},   {"put-dc", "idct_dc.bin", Entry::put},
      {"add-dense", "idct_dense.bin", Entry::add},     {"add-sparse", "idct_sparse.bin", Entry::add},
      {"put_dc-dc", "idct_dc.bin", Entry::put_dc},     {"add_dc-dc", "idct_dc.bin", Entry::add_dc},
  };
  vds::board::log(Line().str("m4 counter resolution=").dec(vds::board::instruction_resolution()).str("\n").c_str());
  for (const Case& c : cases) {
    uint32_t blocks = 0, hash = 0, unused = 0;
    uint64_t overhead = 0, spent = 0;
    // The same loop calling an empty function: the overhead to subtract.
    if (!run_case(c, Entry::none, &blocks, &overhead, &unused) || !run_case(c, c.entry, &blocks, &spent, &hash)) {
      vds::board::log(Line().str("m4 error: cannot read ").str(c.file).str("\n").c_str());
      return 1;
    }
    const uint64_t centi = (spent - overhead) * 100 / blocks;
    Line l;
    l.str("m4 case=").str(c.name).str(" blocks=").dec(blocks).str(" instr_per_call=").dec(centi / 100).str(".");
    l.dec(centi % 100 / 10).dec(centi % 10).str(" checksum=0x").hex32(hash).str("\n");
    vds::board::log(l.c_str());
  }
  return 0;
}
