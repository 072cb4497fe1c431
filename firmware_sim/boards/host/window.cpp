// The host board's live window on SDL2 (see window.h).
#include "window.h"

#if VDS_HAVE_SDL2
#include <SDL2/SDL.h>
#endif

namespace vds::board {

#if VDS_HAVE_SDL2

struct Window::Impl {
  SDL_Window* window = nullptr;
  SDL_Renderer* renderer = nullptr;
  SDL_Texture* texture = nullptr;
  int width = 0, height = 0;
  bool closed = false;
  int drag_x = 0, drag_y = 0;  // mouse motion with the left button held, since controls() last read it
  // Takes the window's events: a close, the mouse dragged.
  void pump() {
    SDL_Event e;
    while (SDL_PollEvent(&e)) {
      if (e.type == SDL_QUIT) closed = true;
      if (e.type == SDL_MOUSEMOTION && (e.motion.state & SDL_BUTTON_LMASK) != 0) {
        drag_x += e.motion.xrel;
        drag_y += e.motion.yrel;
      }
    }
  }
};

namespace {
void release(Window::Impl* w) {
  if (!w) return;
  if (w->texture) SDL_DestroyTexture(w->texture);
  if (w->renderer) SDL_DestroyRenderer(w->renderer);
  if (w->window) SDL_DestroyWindow(w->window);
  SDL_Quit();
  delete w;
}
}  // namespace

Window::~Window() { release(impl_); }

bool Window::open(int width, int height, int scale, std::string* error) {
  if (SDL_Init(SDL_INIT_VIDEO) != 0) {
    *error = std::string("window: SDL cannot start video: ") + SDL_GetError();
    return false;
  }
  auto* w = new Impl;
  w->width = width;
  w->height = height;
  w->window = SDL_CreateWindow("vds client (host board)", SDL_WINDOWPOS_UNDEFINED, SDL_WINDOWPOS_UNDEFINED,
                               width * scale, height * scale, 0);
  if (w->window) w->renderer = SDL_CreateRenderer(w->window, -1, SDL_RENDERER_SOFTWARE);
  if (w->renderer)
    w->texture = SDL_CreateTexture(w->renderer, SDL_PIXELFORMAT_RGB24, SDL_TEXTUREACCESS_STREAMING, width, height);
  if (!w->texture) {
    *error = std::string("window: ") + SDL_GetError();
    release(w);
    return false;
  }
  impl_ = w;
  return true;
}

bool Window::show(const io::Image& rgb, uint32_t index) {
  if (!impl_) return false;
  impl_->pump();
  if (impl_->closed) return false;
  if (rgb.width == impl_->width && rgb.height == impl_->height && rgb.channels == 3) {
    SDL_UpdateTexture(impl_->texture, nullptr, rgb.pixels.data(), rgb.width * 3);
    SDL_RenderClear(impl_->renderer);
    SDL_RenderCopy(impl_->renderer, impl_->texture, nullptr, nullptr);
    SDL_RenderPresent(impl_->renderer);
  }
  const std::string title = "vds client (host board): frame " + std::to_string(index);
  SDL_SetWindowTitle(impl_->window, title.c_str());
  return true;
}

bool Window::active() {
  if (!impl_) return false;
  impl_->pump();
  return !impl_->closed;
}

bool Window::controls(terrain::SteerInput* in) {
  if (!impl_) return false;
  impl_->pump();
  if (impl_->closed) return false;
  const Uint8* k = SDL_GetKeyboardState(nullptr);
  const auto axis = [k](SDL_Scancode plus, SDL_Scancode plus2, SDL_Scancode minus, SDL_Scancode minus2) {
    return static_cast<int8_t>((k[plus] || k[plus2] ? 1 : 0) - (k[minus] || k[minus2] ? 1 : 0));
  };
  constexpr int kKeyTurn = 364;   // 2 degrees a frame, in 2^-16 turn
  constexpr int kDragTurn = 46;   // a quarter of a degree a pixel dragged
  in->forward = axis(SDL_SCANCODE_W, SDL_SCANCODE_UP, SDL_SCANCODE_S, SDL_SCANCODE_DOWN);
  in->right = axis(SDL_SCANCODE_D, SDL_SCANCODE_D, SDL_SCANCODE_A, SDL_SCANCODE_A);
  in->up = axis(SDL_SCANCODE_R, SDL_SCANCODE_PAGEUP, SDL_SCANCODE_F, SDL_SCANCODE_PAGEDOWN);
  const int turn = axis(SDL_SCANCODE_LEFT, SDL_SCANCODE_LEFT, SDL_SCANCODE_RIGHT, SDL_SCANCODE_RIGHT) * kKeyTurn -
                   impl_->drag_x * kDragTurn;
  const int tilt = -impl_->drag_y * kDragTurn;
  in->turn = static_cast<int16_t>(turn < -16384 ? -16384 : (turn > 16384 ? 16384 : turn));
  in->tilt = static_cast<int16_t>(tilt < -16384 ? -16384 : (tilt > 16384 ? 16384 : tilt));
  in->fast = k[SDL_SCANCODE_LSHIFT] || k[SDL_SCANCODE_RSHIFT];
  impl_->drag_x = impl_->drag_y = 0;
  return in->any();
}

#else

struct Window::Impl {};

Window::~Window() = default;

bool Window::open(int, int, int, std::string* error) {
  *error = "window: this build has no SDL2 (install libsdl2-dev and rebuild)";
  return false;
}

bool Window::show(const io::Image&, uint32_t) { return false; }

bool Window::controls(terrain::SteerInput*) { return false; }

bool Window::active() { return false; }

#endif

}  // namespace vds::board
