// The board interface: everything the client firmware needs from the
// hardware, and nothing more. One implementation per board
// (boards/qemu_mps2_an386, boards/host); porting vds to real hardware means
// writing these functions for it (docs/firmware.md).
#pragma once
#include <cstddef>
#include <cstdint>

namespace vds::board {

// Brings up clocks, the UART and the counter. Called once, first.
void init();

// Bytes received on the UART since the last call, up to `max`; never blocks.
size_t uart_read(uint8_t* buf, size_t max);
// Sends `n` bytes; blocks until the UART has taken them all.
void uart_write(const uint8_t* data, size_t n);

// Milliseconds since init (wraps after 49 days).
uint32_t millis();
// A monotonic count of executed instructions (QEMU -icount) or CPU cycles;
// 0 on a board that has neither. Differences measure work.
uint64_t instructions();
// Resolution of instructions(), in instructions per tick (1 if exact).
uint32_t instruction_resolution();

// A line of text for people watching (semihosting console, stderr).
void log(const char* text);

// Ends the program with `code` as the process / QEMU exit status.
[[noreturn]] void exit(int code);

// For benchmarks and tests only: reads up to `max` bytes at `offset` of a
// file on the machine running the board (semihosting under QEMU, the file
// system on the host board). Returns the bytes read, or -1.
int32_t host_file_read(const char* path, uint32_t offset, uint8_t* buf, uint32_t max);

// Stack high-water mark in bytes (the stack is painted at reset); 0 if the
// board cannot tell.
size_t stack_high_water();

}  // namespace vds::board
