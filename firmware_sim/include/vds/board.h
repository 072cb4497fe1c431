// The board interface: everything the client firmware needs from the
// hardware, and nothing more. One implementation per board
// (boards/qemu_mps2_an386, boards/host); porting vds to real hardware means
// writing these functions for it (docs/firmware.md).
#pragma once
#include <cstddef>
#include <cstdint>

namespace vds::terrain {
struct SteerInput;  // vds/terrain_client.h
}  // namespace vds::terrain

namespace vds::board {

// Brings up clocks, the UART and the counter. Called once, first.
void init();

// Bytes received on the UART since the last call, up to `max`; never blocks.
size_t uart_read(uint8_t* buf, size_t max);
// Sends `n` bytes; blocks until the UART has taken them all.
void uart_write(const uint8_t* data, size_t n);
// Bytes the UART's receive ring holds between the line and uart_read. The
// application declares it to the host's link, which then never has more
// than this on the line unread, so the ring cannot overflow by its doing.
uint16_t uart_rx_ring_bytes();

// True once the far end of the UART has gone away for good (the host
// board's pty or socket peer closed after traffic); never on hardware, where
// a silent line is only silent.
bool uart_closed();

// Sleeps until something may have happened (a UART byte, a timer tick) or
// `max_ms` passed. Busy boards may return at once.
void wait_for_event(uint32_t max_ms);

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

// The display. Frames arrive as horizontal bands of RGB565 pixels, top to
// bottom; the board shows, stores or discards them. `frame_crc` is the
// CRC-32C the application computed over the frame (docs/firmware.md).
void display_begin_frame(uint16_t width, uint16_t height);
void display_band(uint16_t y0, uint16_t rows, const uint16_t* rgb565, size_t stride_pixels);
void display_end_frame(uint32_t frame_crc);

// The viewer's controls (keys, a stick, a mouse), read once a frame (a
// terrain stream) or every viewer's poll (a model the viewer turns): false
// when the board has none or they do not move the viewer this time.
bool read_controls(terrain::SteerInput* in);
// Whether a viewer is still there to steer (a live window open, controls
// left in a script): a model stays in view for them after its stream.
bool viewer_present();

// The workspace budget of this run, bytes: the application must not use
// more (a compile-time constant on hardware, an option on the host board).
size_t workspace_budget();

// For benchmarks and tests only: reads up to `max` bytes at `offset` of a
// file on the machine running the board (semihosting under QEMU, the file
// system on the host board). Returns the bytes read, or -1.
int32_t host_file_read(const char* path, uint32_t offset, uint8_t* buf, uint32_t max);

// Stack high-water mark in bytes (the stack is painted at reset); 0 if the
// board cannot tell.
size_t stack_high_water();

}  // namespace vds::board
