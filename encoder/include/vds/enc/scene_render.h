// vds encoder: ground truth of a walkthrough. Draws a scene (vds/enc/scene.h)
// from a camera pose as a viewer holding the whole scene would see it: every
// texture at full resolution times its lightmap (with the map's overbright),
// trilinear mip-mapping with up to max_aniso samples along the footprint's
// long axis where it is stretched, n x n supersampling, additive effect
// surfaces added, alpha-tested surfaces cut out; and, at the output
// resolution, the triangle seen at each pixel centre and its depth (the
// visibility the walkthrough encoder works from).
//
// The camera (SceneCamera): pixel (i, j) has its centre at (i + 1/2, j + 1/2);
// camera space is x right, y down, z forward along the view; the principal
// point is the image centre and pixels are square, the horizontal field of
// view spanning the image's width. A pose is Quake's: yaw about +Z from +X,
// pitch up from the horizon, no roll.
#pragma once
#include <array>
#include <cstdint>
#include <functional>
#include <utility>
#include <vector>

#include "vds/enc/camera_path.h"
#include "vds/enc/scene.h"
#include "vds/io/image.h"

namespace vds::enc {

struct RenderOptions {
  int width = 240, height = 180;
  int supersample = 2;      // n x n samples per pixel, box-filtered
  int max_aniso = 8;        // samples along a stretched footprint (1: plain trilinear)
  int overbright_bits = 2;  // lightmaps and vertex colours x 2^bits, clamped keeping their hue (the game's
                            // r_mapOverBrightBits), for scenes with Scene::overbright
  double near_m = 1.0 / 32;  // the near clipping plane, metres (a Quake map unit)
  double near_z = 0;         // the same in the scene's units (set by SceneRenderer)
  // Over 1: each frame also says which triangle each pixel shows once the
  // triangles covering fewer pixels than this are left out (SceneFrame::large_ids).
  uint32_t min_pixels = 0;
};

struct SceneCamera {
  std::array<double, 3> position{};
  std::array<double, 3> right{}, down{}, forward{};  // world directions of the camera axes
  double focal = 0, cx = 0, cy = 0;                  // pixels
  int width = 0, height = 0;
};
SceneCamera scene_camera(const CameraPose& pose, double hfov_deg, int width, int height);

constexpr uint32_t kNoTriangle = 0xFFFFFFFFu;

struct SceneFrame {
  io::Image rgb;               // width x height RGB
  std::vector<uint32_t> ids;   // triangle (Scene::indices / 3) seen at each pixel centre, kNoTriangle for none
  std::vector<float> depth;    // its camera-space z (map units), +infinity for none
  // With RenderOptions::min_pixels m > 1: the triangle seen at each pixel
  // centre when those covering fewer than m pixels of `ids` are left out.
  std::vector<uint32_t> large_ids;
};

// The triangles a frame shows, each with the pixels it covers, by triangle.
std::vector<std::pair<uint32_t, uint32_t>> visible_triangles(const SceneFrame& f);

// The same for a client that leaves out the small triangles (covering
// fewer pixels than the frame's RenderOptions::min_pixels) wherever large
// triangles the frame shows lie behind each of their pixels: those pixels
// count for the triangles behind. A small triangle stays if at one of its
// pixels nothing large lies behind it (leaving it out would open a hole),
// or a large triangle the frame does not show elsewhere (it would be drawn
// for the small one's pixels alone, seen through a grille of them). Frames
// rendered without min_pixels: visible_triangles(f).
std::vector<std::pair<uint32_t, uint32_t>> visible_large_triangles(const SceneFrame& f);

// The triangle that client draws at each pixel (kNoTriangle: none): a
// small triangle where it stays, else the large one behind it; what
// visible_large_triangles counts. Frames rendered without min_pixels: f.ids.
std::vector<uint32_t> drawn_triangle_ids(const SceneFrame& f);

// The triangles of a per-pixel buffer, each with the pixels it covers, by
// triangle (kNoTriangle left out).
std::vector<std::pair<uint32_t, uint32_t>> triangle_pixels(const std::vector<uint32_t>& ids);

class SceneRenderer {
 public:
  // `images[t]` is texture t's image (RGBA; empty: drawn mid grey).
  SceneRenderer(const Scene& scene, std::vector<io::Image> images, const RenderOptions& o = RenderOptions{});
  ~SceneRenderer();
  SceneRenderer(const SceneRenderer&) = delete;
  SceneRenderer& operator=(const SceneRenderer&) = delete;
  // Thread-safe: any number of frames may be drawn at once.
  SceneFrame render(const CameraPose& pose, double hfov_deg) const;
  const RenderOptions& options() const { return opt_; }

  struct Prepared;

 private:
  RenderOptions opt_;
  Prepared* p_;
};

// Renders every frame of `path` on `threads` threads (0: one per core) and
// hands them to `sink` in frame order; `progress(done)` is called as frames
// finish (from the calling thread). Memory: a few frames per thread.
void render_path(const SceneRenderer& r, const CameraPath& path, int threads,
                 const std::function<void(size_t frame, const SceneFrame& f)>& sink,
                 const std::function<void(size_t done)>& progress = nullptr);

// The images of a scene's textures, read from where load_scene found them
// (RGBA; empty where a texture has no file). Throws naming a file that
// does not decode.
std::vector<io::Image> load_scene_images(const Scene& s);

}  // namespace vds::enc
