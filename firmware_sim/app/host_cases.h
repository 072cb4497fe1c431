// Benchmark firmware inputs: numbered stream files the host puts in the
// working folder ("walk_case0.vds", "walk_case1.vds", ...), read through
// the board's host file access.
#pragma once
#include <cstddef>
#include <cstdint>

#include "vds/board.h"
#include "vds/player.h"

namespace vds::fw {

// Feeds the host file `path` to an initialised player `buf_bytes` at a
// time (after `s`, the status init returned): the player's final status,
// io_error if the file cannot be read.
inline Status play_host_file(Player& player, Status s, const char* path, uint8_t* buf, uint32_t buf_bytes) {
  uint32_t offset = 0;
  while (s == Status::ok || s == Status::more_input) {
    const int32_t got = board::host_file_read(path, offset, buf, buf_bytes);
    if (got < 0) return Status::io_error;
    if (got == 0) return player.finish();
    offset += static_cast<uint32_t>(got);
    s = player.feed(buf, static_cast<size_t>(got));
    if (s == Status::ok) break;
  }
  return s;
}

// Whether the host has a file at `path` with at least one byte.
inline bool host_file_exists(const char* path) {
  uint8_t b = 0;
  return board::host_file_read(path, 0, &b, 1) > 0;
}

// The part of `path` after its last '/'.
inline const char* file_name(const char* path) {
  const char* base = path;
  for (const char* p = path; *p; ++p)
    if (*p == '/') base = p + 1;
  return base;
}

// Calls run(name) for "<stem>0.vds", "<stem>1.vds", ... (at most ten)
// until run returns false (the file is missing); returns how many ran.
// `stem` is at most 20 characters.
template <typename Run>
int run_cases(const char* stem, Run run) {
  char name[32];
  int n = 0;
  while (stem[n] != 0 && n < 20) name[n] = stem[n], ++n;
  int cases = 0;
  for (; cases < 10; ++cases) {
    name[n] = static_cast<char>('0' + cases);
    name[n + 1] = '.', name[n + 2] = 'v', name[n + 3] = 'd', name[n + 4] = 's', name[n + 5] = 0;
    if (!run(name)) break;
  }
  return cases;
}

}  // namespace vds::fw
