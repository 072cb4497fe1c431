// Cortex-M4 run of the bench_idct cases under QEMU (mps2-an386 with
// -icount shift=0): instructions per call from SysTick, and checksums of the
// written bytes to compare with the host build (bit-exactness across targets).
//
// Reads idct_dense.bin, idct_sparse.bin and idct_dc.bin (bench_idct --dump)
// from QEMU's working directory through semihosting and prints one line per
// case. bench/run_idct.sh builds and runs it; see bench/results/idct.md.
#include <cstddef>
#include <cstdint>
#include <cstring>

#include "vds/idct.h"

namespace {

// ---- semihosting (ARM semihosting spec, BKPT 0xAB on M-profile) ----------
constexpr int kSysOpen = 0x01, kSysClose = 0x02, kSysWrite0 = 0x04, kSysRead = 0x06, kSysFlen = 0x0c,
              kSysExit = 0x18;
constexpr uint32_t kAdpStoppedApplicationExit = 0x20026;
constexpr uint32_t kAdpStoppedRunTimeError = 0x20023;

int semihost(int op, const void* arg) {
  register int r0 asm("r0") = op;
  register const void* r1 asm("r1") = arg;
  asm volatile("bkpt 0xab" : "+r"(r0) : "r"(r1) : "memory");
  return r0;
}

void puts_(const char* s) { semihost(kSysWrite0, s); }

[[noreturn]] void exit_(bool ok) {
  semihost(kSysExit, reinterpret_cast<const void*>(ok ? kAdpStoppedApplicationExit : kAdpStoppedRunTimeError));
  for (;;) {
  }
}

// Appends decimal / hex to a line buffer.
struct Line {
  char buf[160];
  size_t n = 0;
  Line& s(const char* t) {
    while (*t && n + 1 < sizeof buf) buf[n++] = *t++;
    buf[n] = 0;
    return *this;
  }
  Line& u(uint32_t v) {
    char tmp[12];
    int k = 0;
    do {
      tmp[k++] = static_cast<char>('0' + v % 10);
      v /= 10;
    } while (v);
    while (k && n + 1 < sizeof buf) buf[n++] = tmp[--k];
    buf[n] = 0;
    return *this;
  }
  Line& x(uint32_t v) {
    s("0x");
    for (int i = 7; i >= 0 && n + 1 < sizeof buf; --i) buf[n++] = "0123456789abcdef"[(v >> (4 * i)) & 15];
    buf[n] = 0;
    return *this;
  }
};

// ---- SysTick as an instruction counter ----------------------------------
// With -icount shift=0 QEMU advances virtual time 1 ns per instruction and
// SysTick counts the 25 MHz system clock, so one tick is 40 instructions;
// calibrate() measures the ratio instead of assuming it.
volatile uint32_t* const kSystCsr = reinterpret_cast<volatile uint32_t*>(0xe000e010);
volatile uint32_t* const kSystRvr = reinterpret_cast<volatile uint32_t*>(0xe000e014);
volatile uint32_t* const kSystCvr = reinterpret_cast<volatile uint32_t*>(0xe000e018);
constexpr uint32_t kSystMask = 0x00ffffff;  // 24-bit down-counter

void systick_start() {
  *kSystRvr = kSystMask;
  *kSystCvr = 0;
  *kSystCsr = 5;  // enable, processor clock, no interrupt
}
uint32_t systick_now() { return *kSystCvr; }
uint32_t ticks_between(uint32_t a, uint32_t b) { return (a - b) & kSystMask; }

// 1000 iterations of 100 NOPs + SUBS + BNE: exactly 102000 instructions.
__attribute__((noinline)) uint32_t calibrate_ticks() {
  const uint32_t t0 = systick_now();
  uint32_t n = 1000;
  asm volatile(
      "1:\n"
      ".rept 100\n nop\n .endr\n"
      "subs %0, %0, #1\n"
      "bne 1b\n"
      : "+r"(n)
      :
      : "cc");
  return ticks_between(t0, systick_now());
}
constexpr uint32_t kCalibInstructions = 102000;

// ---- the cases (same block sets and plane geometry as bench/src/idct.cpp) --
constexpr int kMaxBlocks = 4000;
constexpr ptrdiff_t kStride = 256;
constexpr int kPlaneRows = 64;

int16_t g_blocks[kMaxBlocks * 64];
int16_t g_out[kMaxBlocks * 64];
uint8_t g_plane[kStride * kPlaneRows];

enum class Entry { none, store, put, add, put_dc, add_dc };

__attribute__((noinline)) void null_entry(const int16_t*, uint8_t*, ptrdiff_t) { asm volatile(""); }

uint8_t* block_dst(size_t i) {
  const size_t per_band = kStride / 8;
  return g_plane + (i % per_band) * 8 + ((i / per_band) % (kPlaneRows / 8)) * 8 * kStride;
}

template <Entry kEntry>
__attribute__((noinline)) uint32_t run_blocks(int n) {
  const uint32_t t0 = systick_now();
  for (int i = 0; i < n; ++i) {
    uint8_t* dst = block_dst(static_cast<size_t>(i));
    const int16_t* coef = g_blocks + 64 * i;
    if constexpr (kEntry == Entry::none) {
      null_entry(coef, dst, kStride);
    } else if constexpr (kEntry == Entry::store) {
      vds::idct8x8(coef, g_out + 64 * i);
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
  return ticks_between(t0, systick_now());
}

uint32_t fnv(uint32_t h, const uint8_t* p, size_t n) {
  for (size_t i = 0; i < n; ++i) h = (h ^ p[i]) * 16777619u;
  return h;
}

int load_set(const char* file) {
  struct {
    const char* name;
    uint32_t mode;
    uint32_t len;
  } open_args = {file, 1 /* "rb" */, static_cast<uint32_t>(std::strlen(file))};
  const int fd = semihost(kSysOpen, &open_args);
  if (fd < 0) return -1;
  const uint32_t flen_args[1] = {static_cast<uint32_t>(fd)};
  const int len = semihost(kSysFlen, flen_args);
  int n = len / 128;
  if (n > kMaxBlocks) n = kMaxBlocks;
  const uint32_t read_args[3] = {static_cast<uint32_t>(fd), reinterpret_cast<uint32_t>(g_blocks),
                                 static_cast<uint32_t>(n * 128)};
  const int not_read = semihost(kSysRead, read_args);
  semihost(kSysClose, flen_args);
  // Little-endian file, little-endian target: the bytes are the int16 values.
  return not_read == 0 ? n : -1;
}

struct Case {
  const char* name;
  const char* file;
  Entry entry;
};

template <Entry kEntry>
uint32_t run(int n) {
  return run_blocks<kEntry>(n);
}

uint32_t dispatch(Entry e, int n) {
  switch (e) {
    case Entry::none: return run<Entry::none>(n);
    case Entry::store: return run<Entry::store>(n);
    case Entry::put: return run<Entry::put>(n);
    case Entry::add: return run<Entry::add>(n);
    case Entry::put_dc: return run<Entry::put_dc>(n);
    case Entry::add_dc: return run<Entry::add_dc>(n);
  }
  return 0;
}

}  // namespace

int bench_main() {
  static const Case cases[] = {
      {"store-dense", "idct_dense.bin", Entry::store},  {"store-sparse", "idct_sparse.bin", Entry::store},
      {"store-dc", "idct_dc.bin", Entry::store},        {"put-dense", "idct_dense.bin", Entry::put},
      {"put-sparse", "idct_sparse.bin", Entry::put},    {"put-dc", "idct_dc.bin", Entry::put},
      {"add-dense", "idct_dense.bin", Entry::add},      {"add-sparse", "idct_sparse.bin", Entry::add},
      {"put_dc-dc", "idct_dc.bin", Entry::put_dc},      {"add_dc-dc", "idct_dc.bin", Entry::add_dc},
  };
  systick_start();
  const uint32_t calib = calibrate_ticks();
  if (calib == 0) {
    puts_("m4 error: SysTick does not advance (run QEMU with -icount shift=0)\n");
    exit_(false);
  }
  Line hdr;
  puts_(hdr.s("m4 calibration instructions=").u(kCalibInstructions).s(" ticks=").u(calib).s("\n").buf);
  for (const Case& c : cases) {
    const int n = load_set(c.file);
    if (n <= 0) {
      Line e;
      puts_(e.s("m4 error: cannot read ").s(c.file).s("\n").buf);
      exit_(false);
    }
    std::memset(g_plane, 128, sizeof g_plane);
    // The loop with a call of an empty function: the overhead to subtract.
    const uint32_t overhead = dispatch(Entry::none, n);
    std::memset(g_plane, 128, sizeof g_plane);
    const uint32_t ticks = dispatch(c.entry, n);
    uint32_t h = 2166136261u;
    if (c.entry == Entry::store)
      h = fnv(h, reinterpret_cast<const uint8_t*>(g_out), static_cast<size_t>(n) * 128);
    else
      h = fnv(h, g_plane, sizeof g_plane);
    // Instructions per call, in hundredths: (ticks - overhead) * instr/tick / n.
    const uint64_t num = static_cast<uint64_t>(ticks - overhead) * kCalibInstructions * 100;
    const uint32_t centi = static_cast<uint32_t>(num / (static_cast<uint64_t>(calib) * static_cast<uint32_t>(n)));
    Line l;
    l.s("m4 case=").s(c.name).s(" blocks=").u(static_cast<uint32_t>(n)).s(" instr_per_call=").u(centi / 100).s(".");
    l.u(centi % 100 / 10).u(centi % 10).s(" checksum=").x(h).s("\n");
    puts_(l.buf);
  }
  exit_(true);
}

extern "C" {
extern uint32_t __stack_top;
[[noreturn]] void reset_handler() {
  bench_main();
  exit_(true);
}
[[noreturn]] void fault_handler() {
  puts_("m4 error: fault\n");
  exit_(false);
}
// Cortex-M vector table: initial stack pointer, reset, then the faults.
__attribute__((section(".vectors"), used)) const void* const g_vectors[16] = {
    &__stack_top,
    reinterpret_cast<const void*>(reset_handler),
    reinterpret_cast<const void*>(fault_handler),  // NMI
    reinterpret_cast<const void*>(fault_handler),  // HardFault
    reinterpret_cast<const void*>(fault_handler),  // MemManage
    reinterpret_cast<const void*>(fault_handler),  // BusFault
    reinterpret_cast<const void*>(fault_handler),  // UsageFault
};
}
