// The host-native board: the client firmware in an ordinary process.
// Its UART is any link backend (pty, TCP; see transport/host), paced at a
// chosen baud rate; its display writes PNG frames, a Y4M video and a
// contact sheet, and shows them in a live window (SDL2) on request; its
// workspace budget is a run-time option. The console is stdout. There is no
// instruction counter (count with callgrind instead). The viewer's controls
// come from the live window's keys and mouse, or from a controls script.
#include <unistd.h>

#include <CLI/CLI.hpp>
#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <memory>
#include <stdexcept>
#include <string>
#include <thread>
#include <vector>

#include "vds/board.h"
#include "vds/io/image.h"
#include "vds/io/y4m.h"
#include "vds/link/backend.h"
#include "vds/link/fd_backends.h"
#include "controls_script.h"
#include "window.h"

extern "C" int vds_app_main();

namespace vds::board {
namespace {

using Clock = std::chrono::steady_clock;

struct Options {
  std::string uart;            // backend spec, "pty-new", or "" (no UART)
  uint32_t baud = 115200;      // 0: unpaced
  std::string frames_dir;      // one PNG per frame
  std::string y4m;             // the whole run as a Y4M video
  std::string contact_sheet;   // thumbnails of every frame in one PNG
  size_t workspace = 256 * 1024;
  int contact_columns = 6;
  bool window = false;         // live window (SDL2)
  int window_scale = 2;
  bool hold = false;           // after a model's stream, keep it in view until the window is closed
  std::string controls;        // a controls script (read_controls), instead of the window's keys
};

Options g_opt;
Clock::time_point g_start;
// The controls script, one entry a frame; g_control_next the next to read.
std::vector<terrain::SteerInput> g_script;
size_t g_control_next = 0;

// The controls script's file, read whole (controls_script.h).
std::vector<terrain::SteerInput> read_controls_script(const std::string& path) {
  constexpr size_t kMaxBytes = size_t{16} << 20;
  std::ifstream f(path, std::ios::binary);
  if (!f) throw std::runtime_error(path + ": cannot read the controls script");
  std::string text(kMaxBytes + 1, '\0');
  f.read(text.data(), static_cast<std::streamsize>(text.size()));
  text.resize(static_cast<size_t>(f.gcount()));
  if (text.size() > kMaxBytes) throw std::runtime_error(path + ": a controls script over 16 MiB");
  return parse_controls_script(text, path);
}
std::unique_ptr<link::Backend> g_uart;
Window g_window;
bool g_uart_traffic = false;  // a byte has arrived: the host is there
bool g_uart_closed = false;   // and has gone since

// Receive pacing: a UART moves one byte per 10 bit times (start, 8 data,
// stop). Transmission is paced by the backend itself (FdBackend::set_pacing).
double g_rx_credit = 0;
Clock::time_point g_last_pace;
constexpr double kBitsPerByte = 10.0;
// Bytes that arrive while the firmware is busy wait in a receive ring filled
// by the UART interrupt, as on the Cortex-M4 board (4 KiB there too): the
// firmware then takes them at once. A smaller allowance would throw away
// line time for every stall, so the board would drain slower than the
// line delivers.
constexpr double kMaxCreditBytes = 4096.0;

void refill_credit() {
  const Clock::time_point now = Clock::now();
  const double seconds = std::chrono::duration<double>(now - g_last_pace).count();
  g_last_pace = now;
  const double bytes = seconds * g_opt.baud / kBitsPerByte;
  g_rx_credit = std::min(g_rx_credit + bytes, kMaxCreditBytes);
}

// The display.
uint16_t g_width = 0, g_height = 0;
std::vector<uint8_t> g_rgb;  // RGB888 of the frame being drawn
uint32_t g_frame_index = 0;
std::vector<io::Image> g_thumbs;
std::unique_ptr<io::Y4mWriter> g_y4m;

io::Image thumbnail(const io::Image& img, int scale) {
  io::Image t(std::max(1, img.width / scale), std::max(1, img.height / scale), 3);
  for (int y = 0; y < t.height; ++y)
    for (int x = 0; x < t.width; ++x)
      for (int c = 0; c < 3; ++c) {
        int sum = 0;
        for (int dy = 0; dy < scale; ++dy)
          for (int dx = 0; dx < scale; ++dx) sum += img.at(std::min(img.width - 1, x * scale + dx), std::min(img.height - 1, y * scale + dy), c);
        t.at(x, y, c) = static_cast<uint8_t>(sum / (scale * scale));
      }
  return t;
}

void write_contact_sheet() {
  if (g_opt.contact_sheet.empty() || g_thumbs.empty()) return;
  const int cols = std::min<int>(g_opt.contact_columns, static_cast<int>(g_thumbs.size()));
  const int rows = (static_cast<int>(g_thumbs.size()) + cols - 1) / cols;
  const int tw = g_thumbs[0].width, th = g_thumbs[0].height, gap = 4;
  io::Image sheet(cols * tw + (cols + 1) * gap, rows * th + (rows + 1) * gap, 3);
  std::fill(sheet.pixels.begin(), sheet.pixels.end(), 40);
  for (size_t i = 0; i < g_thumbs.size(); ++i) {
    const int cx = gap + static_cast<int>(i % cols) * (tw + gap), cy = gap + static_cast<int>(i / cols) * (th + gap);
    const io::Image& t = g_thumbs[i];
    for (int y = 0; y < std::min(th, t.height); ++y)
      for (int x = 0; x < std::min(tw, t.width); ++x)
        for (int c = 0; c < 3; ++c) sheet.at(cx + x, cy + y, c) = t.at(x, y, c);
  }
  io::save_png(g_opt.contact_sheet, sheet);
}

}  // namespace

void init() {
  g_start = Clock::now();
  g_last_pace = g_start;
}

size_t uart_read(uint8_t* buf, size_t max) {
  if (!g_uart || g_uart_closed) return 0;
  if (g_opt.baud) {
    refill_credit();
    max = std::min(max, static_cast<size_t>(g_rx_credit));
    if (max == 0) return 0;
  }
  size_t n = 0;
  try {
    n = g_uart->read(buf, max, 0);
  } catch (const vds::link::BackendError& e) {
    // A pty master reads EIO while no one holds the other end: before the
    // first byte that is the host not there yet, afterwards it has gone.
    if (e.kind() != vds::link::BackendError::Kind::disconnected) throw;
    if (g_uart_traffic) g_uart_closed = true;
    return 0;
  }
  if (n) g_uart_traffic = true;
  if (g_opt.baud) g_rx_credit -= static_cast<double>(n);
  return n;
}

uint16_t uart_rx_ring_bytes() { return static_cast<uint16_t>(kMaxCreditBytes); }

bool uart_closed() { return g_uart_closed; }

void uart_write(const uint8_t* data, size_t n) {
  if (!g_uart || g_uart_closed) return;
  size_t done = 0;
  while (done < n) {
    const size_t take = std::min(n - done, g_uart->write_room());
    if (take) {
      size_t w = 0;
      try {
        w = g_uart->write(data + done, take);
      } catch (const vds::link::BackendError& e) {
        if (e.kind() != vds::link::BackendError::Kind::disconnected) throw;
        if (g_uart_traffic) {
          g_uart_closed = true;
          return;
        }
      }
      done += w;
      if (w == take) continue;
    }
    std::this_thread::sleep_for(std::chrono::microseconds(200));
  }
}

void wait_for_event(uint32_t max_ms) {
  std::this_thread::sleep_for(std::chrono::microseconds(std::min<uint32_t>(max_ms, 1) * 500));
}

uint32_t millis() {
  return static_cast<uint32_t>(std::chrono::duration_cast<std::chrono::milliseconds>(Clock::now() - g_start).count());
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

void display_begin_frame(uint16_t width, uint16_t height) {
  g_width = width;
  g_height = height;
  g_rgb.assign(static_cast<size_t>(width) * height * 3, 0);
}

void display_band(uint16_t y0, uint16_t rows, const uint16_t* rgb565, size_t stride_pixels) {
  for (uint16_t r = 0; r < rows && y0 + r < g_height; ++r)
    for (uint16_t x = 0; x < g_width; ++x)
      io::rgb565_to_rgb888(rgb565[r * stride_pixels + x], &g_rgb[(static_cast<size_t>(y0 + r) * g_width + x) * 3]);
}

void display_end_frame(uint32_t frame_crc) {
  (void)frame_crc;
  io::Image img(g_width, g_height, 3);
  img.pixels = g_rgb;
  if (!g_opt.frames_dir.empty()) {
    char name[32];
    std::snprintf(name, sizeof name, "/frame%04u.png", g_frame_index);
    io::save_png(g_opt.frames_dir + name, img);
  }
  if (!g_opt.y4m.empty()) {
    if (!g_y4m) g_y4m = std::make_unique<io::Y4mWriter>(g_opt.y4m);
    g_y4m->write(img);
  }
  if (!g_opt.contact_sheet.empty()) g_thumbs.push_back(thumbnail(img, 2));
  if (g_opt.window) {
    std::string error;
    if (!g_window.is_open() && !g_window.open(g_width, g_height, g_opt.window_scale, &error)) {
      std::fprintf(stderr, "vds board: %s; going on without it\n", error.c_str());
      g_opt.window = false;
    } else if (!g_window.show(img, g_frame_index)) {
      g_opt.window = false;  // closed by the user; the run goes on
    }
  }
  ++g_frame_index;
}

bool read_controls(terrain::SteerInput* in) {
  if (!g_opt.controls.empty()) {
    if (g_control_next >= g_script.size()) return false;
    *in = g_script[g_control_next++];
    return in->any();
  }
  return g_opt.window && g_window.controls(in);
}

bool viewer_present() {
  if (!g_opt.controls.empty()) return g_control_next < g_script.size();
  return g_opt.hold && g_opt.window && g_window.active();
}

size_t workspace_budget() { return g_opt.workspace; }

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

int main(int argc, char** argv) {
  using vds::board::g_opt;
  CLI::App app{"vds client firmware on the host-native board"};
  app.add_option("--uart", g_opt.uart,
                 "UART: pty:PATH | pty-new (create a pair, print the other end) | tcp:HOST:PORT | tcp-listen:PORT");
  app.add_option("--baud", g_opt.baud, "UART pace in baud, 10 bits per byte (0: unpaced)")->capture_default_str();
  app.add_option("--frames", g_opt.frames_dir, "Directory for one PNG per displayed frame");
  app.add_option("--y4m", g_opt.y4m, "Write the displayed frames as a Y4M video");
  app.add_option("--contact-sheet", g_opt.contact_sheet, "Write thumbnails of all frames to this PNG");
  app.add_option("--workspace", g_opt.workspace, "Workspace budget of the client, bytes")->capture_default_str();
  app.add_flag("--window", g_opt.window, "Show the frames in a live window (SDL2)");
  app.add_option("--window-scale", g_opt.window_scale, "Window pixels per frame pixel")->check(CLI::Range(1, 8))
      ->capture_default_str();
  app.add_flag("--hold", g_opt.hold,
               "With --window: after a model's stream, keep the model in view (the viewer turns it) until the window is closed");
  app.add_option("--controls", g_opt.controls,
                 "The viewer's controls from a script instead of the window's keys: lines 'FRAMES FORWARD RIGHT UP TURN TILT [fast]'");
  CLI11_PARSE(app, argc, argv);
  try {
    if (!g_opt.controls.empty()) vds::board::g_script = vds::board::read_controls_script(g_opt.controls);
    if (!g_opt.frames_dir.empty()) std::filesystem::create_directories(g_opt.frames_dir);
    if (g_opt.uart == "pty-new") {
      vds::link::PtyPair pair = vds::link::open_pty_pair();
      std::fprintf(stderr, "uart: %s\n", pair.slave_path.c_str());
      pair.master->set_pacing(g_opt.baud);  // 0: unpaced
      vds::board::g_uart = std::move(pair.master);
    } else if (!g_opt.uart.empty()) {
      // --baud 0: the line's nominal rate, unpaced.
      vds::board::g_uart = vds::link::open_backend(g_opt.uart, g_opt.baud ? g_opt.baud : 115200, g_opt.baud != 0);
    }
  } catch (const std::exception& e) {
    std::fprintf(stderr, "vds board: %s\n", e.what());
    return 2;
  }
  const int code = vds_app_main();
  try {
    vds::board::write_contact_sheet();
  } catch (const std::exception& e) {
    std::fprintf(stderr, "vds board: %s\n", e.what());
    return code ? code : 1;
  }
  return code;
}
