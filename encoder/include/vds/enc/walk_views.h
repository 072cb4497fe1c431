// vds encoder: which stored view serves each polygon of a walkthrough frame,
// and when a new view must be sent — the view schedule of the walkthrough
// mode (Cohen-Or, Mann, Fleishman, "Deep compression for streaming texture
// intensive animations", section 4).
//
// The client holds `slots` views: images rendered offline at cameras of the
// path (past or future frames). It draws each polygon of a frame mapped from
// the held view whose texture quality factor for it (vds/homography.h:
// the largest magnification of the view -> screen map, here at the vertices
// of the part of the polygon the frame's screen shows, in front of the
// view's near plane, so that polygons reaching behind either camera have a
// factor) is smallest; a polygon the view does not show (not in that
// frame's visibility), or whose part on the screen reaches outside the
// view's image, cannot be served by it. When a frame shows a polygon
// that no held view serves with a factor at most `threshold` (more than
// `tolerance_px` pixels of them), a view update is due at that frame, into
// the slot whose view serves the fewest of the frame's pixels: rendered at
// the camera of a frame up to `lookahead` frames ahead — the one with
// which the views serve the longest run of frames from this one on (views
// from the future are allowed: the stream is precomputed); the frame's own
// camera always serves the frame itself. Magnifications are computed with
// the client's own fixed-point homography (vds/homography.h); the stream
// carries each polygon's choice, so the client need not repeat them.
#pragma once
#include <cstdint>
#include <utility>
#include <vector>

#include "vds/enc/camera_path.h"
#include "vds/enc/scene.h"
#include "vds/render_camera.h"
#include "vds/walk.h"

namespace vds::enc {

// The client's fixed-point camera for a pose (vds/enc/scene_render.h's
// camera model), with clip distances in scene units.
vds::Camera client_camera(const CameraPose& pose, double hfov_deg, int width, int height, double near_z, double far_z);

// The field of view (degrees) whose half angle's tangent is `ratio` times
// hfov_deg's: views `ratio` times wider, or a zoom's narrower ones (16 / zoom).
double scaled_hfov(double hfov_deg, double ratio);

struct WalkViewOptions {
  int slots = 2;
  double threshold = 1.35;  // largest magnification a view may serve with
  int lookahead = 20;       // frames ahead a new view's camera may be taken from
  size_t tolerance_px = 0;  // pixels of a frame that may go unserved before an update is due
  int width = 240, height = 180;
  double near_z = 1, far_z = 4096;  // scene units
  double view_hfov_deg = 0;         // the views' horizontal field of view (0: the path's)
  int view_width = 0, view_height = 0;  // the views' size (0: the frame's)
  // A view is occluded for a polygon of which it sees a share (of its area
  // inside the view, by the view's visibility) this much smaller than the
  // share the screen sees (> 1: no such test). A polygon is drawn from a
  // view that is not occluded for it when one serves it; with
  // occlusion_updates, a frame with more than occlusion_tolerance_px
  // pixels that only occluded views serve gets a view update, like one
  // with pixels no view serves. Off here (unless the per-pixel test's
  // buffers are given: then occlusion_share decides); the walkthrough
  // encoder's defaults (WalkEncodeOptions) turn it on.
  double occlusion_margin = 2;
  bool occlusion_updates = false;
  size_t occlusion_tolerance_px = 0;
  // With the visibility buffers (WalkViewBuffers): a view is occluded for a
  // polygon when more than this share of the polygon's samples on the
  // screen (of those inside the view) lie behind something else there
  // (nearer than the polygon's plane by more than 2 %), and a frame's
  // occluded pixels are those each polygon's view (the one it would be
  // drawn from) hides (occlusion_margin is then not used).
  double occlusion_share = 0.1;
  // Texels around a polygon's footprint in a view counted as read (Update::
  // mcus): the bilinear filter's neighbour and the client's fixed-point
  // cameras.
  double region_margin = 3;
  // Zoomed views: an update may instead take a view whose focal length is
  // `zoom` / 16 times the views' (narrower, with finer texels: at 24, views
  // 1.5 times wider than the screen see what the screen sees) when, from
  // the best camera for it, it serves at least `zoom_run` of the frames the
  // best view at the views' own focal length would, and at least
  // `zoom_min_run` frames (16: never).
  int zoom = kWalkZoomUnit;
  double zoom_run = 0.5;
  int zoom_min_run = 10;
};

struct WalkViewPlan {
  struct Update {
    uint32_t slot;
    uint32_t camera_frame;  // the path frame whose camera the view is rendered at
    uint8_t zoom = kWalkZoomUnit;  // its focal length: the views' times zoom / 16
    // The view's MCUs (16 x 16 texels, raster order) the client samples
    // while the view is in its slot: non-zero where the part of a polygon
    // the plan draws from it, on the screen of a frame it does so, lies in
    // the view, widened by WalkViewOptions::region_margin texels. The rest
    // of the view is never read (a region update need not code it).
    std::vector<uint8_t> mcus;
  };
  std::vector<std::vector<Update>> updates;  // per frame: views to have arrived by that frame
  // Per frame, per visible polygon (as given): the slot that serves it, -1 for none.
  std::vector<std::vector<int8_t>> choice;
  size_t pixels = 0;                // visible pixels over all frames
  size_t pixels_within = 0;         // served with a factor <= threshold
  size_t pixels_sharp = 0;          // served with a factor <= 1 (no magnification)
  size_t pixels_unserved = 0;       // by no held view (a hole until an update arrives)
};

// The visibility buffers themselves, sampled every `step` pixels each way
// (the pixel centres (step i + 1/2, step j + 1/2) of a frame of
// WalkViewOptions::width x height): for each frame, the polygon its screen
// shows at each sample, and the polygon and its depth (camera-space z,
// scene units; +infinity for none) that a view at the frame's camera shows
// there (the views' field of view, the frame's size). With them the
// occlusion test is per pixel: a view is occluded for a polygon where the
// polygon's points on the screen lie, seen from the view, behind something
// else (a pillar, a torch, a model's limb), and the planner counts those
// pixels instead of comparing shares of the polygon's area.
struct WalkViewBuffers {
  int step = 2;
  int width = 0, height = 0;  // samples across and down
  std::vector<std::vector<uint32_t>> screen_ids;  // per frame, width x height (kNoTriangle: none)
  std::vector<std::vector<uint32_t>> view_ids;
  std::vector<std::vector<float>> view_depth;
};

// A width x height buffer sampled as WalkViewBuffers keeps it: the
// samples at (step i, step j).
template <typename T>
std::vector<T> walk_buffer_samples(const std::vector<T>& full, int width, int height, int step) {
  const int w = (width + step - 1) / step, h = (height + step - 1) / step;
  std::vector<T> out;
  out.reserve(static_cast<size_t>(w) * static_cast<size_t>(h));
  for (int j = 0; j < h; ++j)
    for (int i = 0; i < w; ++i) out.push_back(full[static_cast<size_t>(j * step) * static_cast<size_t>(width) + static_cast<size_t>(i * step)]);
  return out;
}

// `visible[f]`: (polygon, pixels it covers) for each polygon frame f shows,
// from the ground truth's visibility buffers; `view_visible[f]` the same
// for a view at frame f's camera when views have a wider field of view
// (nullptr: the same as `visible`); `buffers`: the buffers themselves, for
// the per-pixel occlusion test (nullptr: the test by shares of area).
WalkViewPlan plan_walk_views(const Scene& s, const CameraPath& path,
                             const std::vector<std::vector<std::pair<uint32_t, uint32_t>>>& visible,
                             const WalkViewOptions& o = WalkViewOptions{},
                             const std::vector<std::vector<std::pair<uint32_t, uint32_t>>>* view_visible = nullptr,
                             const WalkViewBuffers* buffers = nullptr);

}  // namespace vds::enc
