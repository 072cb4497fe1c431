// The host board's optional live window: shows each displayed frame as it
// completes. Built with SDL2 when the build finds it; otherwise open()
// reports that the window is not available.
#pragma once
#include <cstdint>
#include <string>

#include "vds/io/image.h"
#include "vds/terrain_client.h"

namespace vds::board {

class Window {
 public:
  Window() = default;
  ~Window();
  Window(const Window&) = delete;
  Window& operator=(const Window&) = delete;
  // Opens a window `scale` times the frame size; false with `error` set
  // when it cannot (no SDL2 in this build, no display).
  bool open(int width, int height, int scale, std::string* error);
  bool is_open() const { return impl_ != nullptr; }
  // Open and not closed by the user (reads the window's events).
  bool active();
  // Shows a frame; false once the user has closed the window.
  bool show(const io::Image& rgb, uint32_t index);
  // The viewer's controls now: W/S or Up/Down forward and back, A/D to the
  // sides, Left/Right turn, R/F or Page Up/Down up and down, Shift fast,
  // and the mouse dragged with its left button held turns and tilts. false
  // when nothing moves the viewer (or the window is closed).
  bool controls(terrain::SteerInput* in);

  struct Impl;

 private:
  Impl* impl_ = nullptr;
};

}  // namespace vds::board
