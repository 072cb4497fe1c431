// Register map of the parts of ARM MPS2 AN386 (Cortex-M4) that vds uses, as
// QEMU's mps2-an386 model implements them: CMSDK APB UART0, CMSDK APB
// timer 0 (both clocked at 25 MHz), and the Cortex-M NVIC.
#pragma once
#include <cstdint>

namespace vds::mps2 {

constexpr uint32_t kSysClockHz = 25000000;  // QEMU's SYSCLK for MPS2 peripherals

struct CmsdkUart {
  volatile uint32_t data;     // 0x00: write to send, read to receive
  volatile uint32_t state;    // 0x04: bit 0 TX full, bit 1 RX full, bits 2/3 overrun
  volatile uint32_t ctrl;     // 0x08: bit 0 TX enable, bit 1 RX enable, bit 2 TX irq, bit 3 RX irq
  volatile uint32_t intstat;  // 0x0C: read status, write 1 to clear
  volatile uint32_t bauddiv;  // 0x10
};
constexpr uint32_t kUartTxFull = 1u << 0;
constexpr uint32_t kUartRxFull = 1u << 1;
constexpr uint32_t kUartTxEnable = 1u << 0;
constexpr uint32_t kUartRxEnable = 1u << 1;
constexpr uint32_t kUartRxIrqEnable = 1u << 3;
constexpr uint32_t kUartIntRx = 1u << 1;

struct CmsdkTimer {
  volatile uint32_t ctrl;     // 0x00: bit 0 enable, bit 3 irq enable
  volatile uint32_t value;    // 0x04: counts down at kSysClockHz
  volatile uint32_t reload;   // 0x08
  volatile uint32_t intstat;  // 0x0C
};
constexpr uint32_t kTimerEnable = 1u << 0;

inline CmsdkUart& uart0() { return *reinterpret_cast<CmsdkUart*>(0x40004000u); }
inline CmsdkTimer& timer0() { return *reinterpret_cast<CmsdkTimer*>(0x40000000u); }
inline CmsdkTimer& timer1() { return *reinterpret_cast<CmsdkTimer*>(0x40001000u); }

constexpr uint32_t kUart0RxIrq = 0;  // TX is 1
constexpr uint32_t kTimer0Irq = 8;
constexpr uint32_t kTimer1Irq = 9;

inline volatile uint32_t& nvic_iser0() { return *reinterpret_cast<volatile uint32_t*>(0xE000E100u); }

}  // namespace vds::mps2
