// Reset and interrupt vectors of the MPS2 AN386 board: copy .data, clear
// .bss, paint the stack (for the high-water mark), run constructors, main.
#include <cstddef>
#include <cstdint>

extern "C" {
extern uint32_t __data_start, __data_end, __data_load, __bss_start, __bss_end;
extern uint32_t __stack_limit, __stack_top;
extern void (*__init_array_start[])();
extern void (*__init_array_end[])();
int vds_app_main();
[[noreturn]] void vds_reset_handler();
[[noreturn]] void vds_reset_continue();
void vds_uart0_rx_irq();
void vds_timer0_irq();
void vds_timer1_irq();
}

namespace vds::board {
[[noreturn]] void exit(int code);
void log(const char* text);
}

namespace {

constexpr uint32_t kStackPaint = 0x5AC3A55Cu;

[[noreturn]] void fault() {
  vds::board::log("vds firmware: hard fault\n");
  vds::board::exit(70);
}

void unused_irq() { fault(); }

}  // namespace

extern "C" [[gnu::naked, noreturn]] void vds_reset_handler() {
  // Paint the stack from its limit up to the current SP before anything
  // uses it; done in assembly because this function's own frame lives there.
  asm volatile(
      "ldr r0, =__stack_limit\n"
      "mov r1, sp\n"
      "ldr r2, =0x5AC3A55C\n"
      "1: cmp r0, r1\n"
      "bhs 2f\n"
      "str r2, [r0], #4\n"
      "b 1b\n"
      "2: b vds_reset_continue\n");
}

extern "C" [[noreturn]] void vds_reset_continue() {
  uint32_t* src = &__data_load;
  for (uint32_t* dst = &__data_start; dst < &__data_end;) *dst++ = *src++;
  for (uint32_t* p = &__bss_start; p < &__bss_end;) *p++ = 0;
  for (void (**f)() = __init_array_start; f < __init_array_end; ++f) (*f)();
  vds::board::exit(vds_app_main());
}

namespace vds::board {
size_t stack_high_water() {
  const uint32_t* p = &__stack_limit;
  while (p < &__stack_top && *p == kStackPaint) ++p;
  return static_cast<size_t>(reinterpret_cast<uintptr_t>(&__stack_top) - reinterpret_cast<uintptr_t>(p));
}
}  // namespace vds::board

using Handler = void (*)();

// 16 system exceptions, then the 32 external interrupts of the AN386.
extern "C" [[gnu::section(".vectors"), gnu::used]] const Handler vds_vectors[16 + 32] = {
    reinterpret_cast<Handler>(&__stack_top),
    vds_reset_handler,
    fault,  // NMI
    fault,  // HardFault
    fault,  // MemManage
    fault,  // BusFault
    fault,  // UsageFault
    nullptr, nullptr, nullptr, nullptr,
    unused_irq,  // SVCall
    unused_irq,  // DebugMonitor
    nullptr,
    unused_irq,  // PendSV
    unused_irq,  // SysTick
    vds_uart0_rx_irq,  // IRQ 0: UART0 RX
    unused_irq, unused_irq, unused_irq, unused_irq, unused_irq, unused_irq, unused_irq,
    vds_timer0_irq,  // IRQ 8: timer 0
    vds_timer1_irq,  // IRQ 9: timer 1
    unused_irq, unused_irq, unused_irq, unused_irq, unused_irq, unused_irq,
    unused_irq, unused_irq, unused_irq, unused_irq, unused_irq, unused_irq, unused_irq, unused_irq,
    unused_irq, unused_irq, unused_irq, unused_irq, unused_irq, unused_irq, unused_irq, unused_irq,
};
