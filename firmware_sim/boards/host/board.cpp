// The host-native board: the firmware in an ordinary process. The console
// is stdout, the exit status the process's, the clock the steady clock.
// There is no instruction counter (instructions() is 0); count on the host
// with callgrind instead.
#include <chrono>
#include <cstdio>
#include <cstdlib>

#include "vds/board.h"

namespace vds::board {
namespace {
std::chrono::steady_clock::time_point g_start;
}

void init() { g_start = std::chrono::steady_clock::now(); }

size_t uart_read(uint8_t*, size_t) { return 0; }
void uart_write(const uint8_t*, size_t) {}

uint32_t millis() {
  return static_cast<uint32_t>(
      std::chrono::duration_cast<std::chrono::milliseconds>(std::chrono::steady_clock::now() - g_start).count());
}
uint64_t instructions() { return 0; }
uint32_t instruction_resolution() { return 0; }

void log(const char* text) {
  std::fputs(text, stdout);
  std::fflush(stdout);
}

void exit(int code) {
  std::fflush(stdout);
  std::exit(code);
}

int32_t host_file_read(const char* path, uint32_t offset, uint8_t* buf, uint32_t max) {
  FILE* f = std::fopen(path, "rb");
  if (!f) return -1;
  int32_t result = -1;
  if (std::fseek(f, static_cast<long>(offset), SEEK_SET) == 0) result = static_cast<int32_t>(std::fread(buf, 1, max, f));
  std::fclose(f);
  return result;
}

size_t stack_high_water() { return 0; }

}  // namespace vds::board
