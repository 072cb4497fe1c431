// The MPS2 AN386 board under QEMU: UART0 with an interrupt-driven receive
// ring (the CMSDK UART holds one byte), timer 0 as the clock and the
// instruction counter (QEMU runs with -icount shift=0: one instruction per
// nanosecond of virtual time, so one 25 MHz tick is 40 instructions), and
// semihosting for the console and the exit status.
#include <cstddef>
#include <cstdint>

#include "mps2_an386.h"

#ifndef VDS_WORKSPACE_BYTES
#error "VDS_WORKSPACE_BYTES (the client's workspace budget) must be set by the build"
#endif
#include "vds/board.h"

namespace {

using namespace vds::mps2;

constexpr uint32_t kRingBytes = 4096;  // power of two; at 1 Mbaud, 40 ms of input
constexpr uint32_t kInstructionsPerTick = 1000000000u / kSysClockHz;  // 40 at -icount shift=0
constexpr uint32_t kTicksPerMs = kSysClockHz / 1000;

uint8_t g_ring[kRingBytes];
volatile uint32_t g_head = 0;  // written by the interrupt
volatile uint32_t g_tail = 0;  // written by uart_read
volatile uint32_t g_overflows = 0;
volatile uint32_t g_timer_wraps = 0;

enum : int {
  kSysOpen = 0x01,
  kSysClose = 0x02,
  kSysWrite0 = 0x04,
  kSysRead = 0x06,
  kSysSeek = 0x0A,
  kSysGetCmdline = 0x15,
  kSysExitExtended = 0x20,
};
constexpr uint32_t kOpenModeReadBinary = 1;  // "rb" in the semihosting mode table
constexpr uint32_t kAdpStoppedApplicationExit = 0x20026;

int semihost(int op, const void* arg) {
  register int r0 asm("r0") = op;
  register const void* r1 asm("r1") = arg;
  asm volatile("bkpt 0xAB" : "+r"(r0) : "r"(r1) : "memory");
  return r0;
}

// The workspace budget of this run: VDS_WORKSPACE_BYTES, or less when the
// semihosting command line (QEMU: -semihosting-config ...,arg=workspace=N)
// asks for it, so one build can be tried at smaller budgets.
size_t g_workspace_budget = VDS_WORKSPACE_BYTES;

void read_budget_from_cmdline() {
  char line[128] = {};
  uint32_t block[2] = {reinterpret_cast<uint32_t>(line), sizeof line - 1};
  if (semihost(kSysGetCmdline, block) != 0) return;
  const char key[] = "workspace=";
  for (uint32_t i = 0; line[i]; ++i) {
    uint32_t k = 0;
    while (key[k] && line[i + k] == key[k]) ++k;
    if (key[k]) continue;
    uint32_t v = 0;
    for (uint32_t j = i + k; line[j] >= '0' && line[j] <= '9' && v < 100000000u; ++j) v = v * 10 + (line[j] - '0');
    if (v > 0 && v < g_workspace_budget) g_workspace_budget = v;
    return;
  }
}

uint64_t ticks() {
  // Read wraps, value, wraps again: a wrap between the reads is seen.
  for (;;) {
    const uint32_t w0 = g_timer_wraps;
    const uint32_t v = timer0().value;
    const uint32_t pending = timer0().intstat & 1u;
    const uint32_t w1 = g_timer_wraps;
    if (w0 != w1) continue;
    // The counter runs down from 0xFFFFFFFF; an unserviced wrap counts too.
    const uint64_t wraps = static_cast<uint64_t>(w0) + (pending && v > 0x80000000u ? 1u : 0u);
    return (wraps << 32) + (0xFFFFFFFFu - v);
  }
}

}  // namespace

extern "C" void vds_uart0_rx_irq() {
  uart0().intstat = kUartIntRx;
  while (uart0().state & kUartRxFull) {
    const uint8_t b = static_cast<uint8_t>(uart0().data);
    const uint32_t h = g_head;
    if (h - g_tail == kRingBytes) {
      g_overflows = g_overflows + 1;  // the link layer retransmits what is lost
      continue;
    }
    g_ring[h & (kRingBytes - 1)] = b;
    g_head = h + 1;
  }
}

// A 1 kHz tick on timer 1 wakes wait_for_event, so link timers run.
extern "C" void vds_timer1_irq() { timer1().intstat = 1; }

extern "C" void vds_timer0_irq() {
  timer0().intstat = 1;
  g_timer_wraps = g_timer_wraps + 1;
}

namespace vds::board {

void init() {
  timer0().ctrl = 0;
  timer0().reload = 0xFFFFFFFFu;
  timer0().value = 0xFFFFFFFFu;
  timer0().ctrl = kTimerEnable | (1u << 3);  // enable, interrupt on wrap
  timer1().ctrl = 0;
  timer1().reload = kTicksPerMs - 1;
  timer1().value = kTicksPerMs - 1;
  timer1().ctrl = kTimerEnable | (1u << 3);
  uart0().bauddiv = 16;
  uart0().ctrl = kUartTxEnable | kUartRxEnable | kUartRxIrqEnable;
  nvic_iser0() = (1u << kUart0RxIrq) | (1u << kTimer0Irq) | (1u << kTimer1Irq);
  asm volatile("cpsie i" ::: "memory");
  read_budget_from_cmdline();
}

size_t uart_read(uint8_t* buf, size_t max) {
  size_t n = 0;
  uint32_t t = g_tail;
  const uint32_t h = g_head;
  while (n < max && t != h) buf[n++] = g_ring[t++ & (kRingBytes - 1)];
  g_tail = t;
  return n;
}

void uart_write(const uint8_t* data, size_t n) {
  for (size_t i = 0; i < n; ++i) {
    while (uart0().state & kUartTxFull) {
    }
    uart0().data = data[i];
  }
}

uint16_t uart_rx_ring_bytes() { return static_cast<uint16_t>(kRingBytes); }
bool uart_closed() { return false; }  // a socket closing is invisible behind the UART

void wait_for_event(uint32_t max_ms) {
  (void)max_ms;  // the UART interrupt or the next timer event ends the wait
  if (g_head == g_tail) asm volatile("wfi" ::: "memory");
}

// No panel on this board: frames are checked by their CRC, which the
// application sends to the host.
void display_begin_frame(uint16_t, uint16_t) {}
void display_band(uint16_t, uint16_t, const uint16_t*, size_t) {}
void display_end_frame(uint32_t) {}

size_t workspace_budget() { return g_workspace_budget; }

uint32_t millis() { return static_cast<uint32_t>(ticks() / kTicksPerMs); }
uint64_t instructions() { return ticks() * kInstructionsPerTick; }
uint32_t instruction_resolution() { return kInstructionsPerTick; }

void log(const char* text) { semihost(kSysWrite0, text); }

// No controls on this board: a flight script steers it.
bool read_controls(terrain::SteerInput*) { return false; }
bool viewer_present() { return false; }

int32_t host_file_read(const char* path, uint32_t offset, uint8_t* buf, uint32_t max) {
  uint32_t len = 0;
  while (path[len]) ++len;
  const uint32_t open_args[3] = {reinterpret_cast<uint32_t>(path), kOpenModeReadBinary, len};
  const int fd = semihost(kSysOpen, open_args);
  if (fd < 0) return -1;
  const uint32_t seek_args[2] = {static_cast<uint32_t>(fd), offset};
  const uint32_t read_args[3] = {static_cast<uint32_t>(fd), reinterpret_cast<uint32_t>(buf), max};
  const uint32_t close_args[1] = {static_cast<uint32_t>(fd)};
  int32_t result = -1;
  if (semihost(kSysSeek, seek_args) == 0) {
    const int not_read = semihost(kSysRead, read_args);  // returns the bytes NOT read
    if (not_read >= 0 && static_cast<uint32_t>(not_read) <= max) result = static_cast<int32_t>(max - static_cast<uint32_t>(not_read));
  }
  semihost(kSysClose, close_args);
  return result;
}

void exit(int code) {
  const uint32_t block[2] = {kAdpStoppedApplicationExit, static_cast<uint32_t>(code)};
  semihost(kSysExitExtended, block);
  for (;;) {
  }
}

}  // namespace vds::board

// The only C library the firmware has: the three memory functions the
// client library may call. Compiled with -fno-builtin so these loops are
// not turned back into calls to themselves.
extern "C" {
void* memcpy(void* d, const void* s, size_t n) {
  auto* o = static_cast<uint8_t*>(d);
  auto* i = static_cast<const uint8_t*>(s);
  if (((reinterpret_cast<uintptr_t>(o) | reinterpret_cast<uintptr_t>(i)) & 3u) == 0) {
    for (; n >= 4; n -= 4, o += 4, i += 4) *reinterpret_cast<uint32_t*>(o) = *reinterpret_cast<const uint32_t*>(i);
  }
  while (n--) *o++ = *i++;
  return d;
}
void* memmove(void* d, const void* s, size_t n) {
  auto* o = static_cast<uint8_t*>(d);
  auto* i = static_cast<const uint8_t*>(s);
  if (o <= i || o >= i + n) return memcpy(d, s, n);
  o += n;
  i += n;
  while (n--) *--o = *--i;
  return d;
}
void* memset(void* d, int c, size_t n) {
  auto* o = static_cast<uint8_t*>(d);
  while (n--) *o++ = static_cast<uint8_t>(c);
  return d;
}
}
