// vds encoder: a walkthrough stream (`vds encode-walk`): a scene and a
// camera path made into the stream the walkthrough client plays
// (vds/walk.h, vds/walk_geometry.h; docs/walkthrough.md).
//
// The encoder renders the ground truth of every frame (vds/enc/scene_render.h)
// for its visibility, plans the geometry (vds/enc/walk_geometry.h) and the
// views (vds/enc/walk_views.h), renders each view at its camera and codes
// it as an intra vds image, at one quality for the whole stream: the best
// whose stream fits the target rate. It then plays the stream through the
// client library's player — what the client will show, frame by frame —
// and measures it against the ground truth.
#pragma once
#include <cstdint>
#include <functional>
#include <string>
#include <vector>

#include "vds/enc/camera_path.h"
#include "vds/enc/scene.h"
#include "vds/enc/scene_render.h"
#include "vds/enc/walk_schedule.h"
#include "vds/link/frame.h"
#include "vds/link/link.h"
#include "vds/walk.h"

namespace vds::enc {

struct WalkEncodeOptions {
  double rate_kbps = 16;  // the whole stream, header included
  int views = 2;          // view slots the client holds
  double threshold = 18;  // largest magnification a view serves (the sweeps on oa_dm4: docs/walkthrough.md)
  int lookahead = 20;     // frames ahead a view's camera may come from
  double view_widen = 1.5;  // tan(half the views' field of view) / tan(half the screen's)
  double view_scale = 2.0 / 3;  // the views' size over the frame's (each side; 16 pixels at least, even)
  int refine_delta = 0;     // a refinement's quality above the views' (0: none; they did not pay on oa_dm4: docs/walkthrough.md)
  int refine_after = 10;    // frames after a view arrives; views serving at least twice that are refined
  int window = 2;         // hot: visible within this many frames either side
  // A triangle covering fewer of a frame's pixels than this is not drawn
  // there where a larger one the frame shows lies behind each of its
  // pixels (visible_large_triangles; 0: every triangle a frame shows is
  // drawn). On the figure maps' tours: fewer triangle slots and set-ups,
  // the pooled PSNR the same or higher (docs/walkthrough.md, "Small triangles").
  uint32_t min_pixels = 16;
  int max_sends = 0;      // polygons a frame sends at most before the rest go a frame earlier (0: no limit)
  int frames_per_record = kWalkMaxFramesPerRecord;  // most frames a WFRM record holds
  // Metres a vertex may move to the grid the geometry is sent on: the
  // coarsest power of two of the scene's unit, from 1 unit down, that keeps
  // every vertex of what the client draws within it.
  double vertex_tolerance_m = 1.0 / 64;
  // View updates ask the client to draw its prediction of the view, and
  // are coded as a residual against it when that pays (rate and
  // distortion); measured not to pay on the figure maps (docs/walkthrough.md).
  bool predict = false;
  // Zoomed view updates (WalkViewOptions::zoom, zoom_run, zoom_min_run; a
  // zoom of 16: none). 24: with views 1.5 times wider than the screen, a
  // zoomed view sees what the screen sees, with texels 1.5 times finer
  // (measured in docs/walkthrough.md, "Zoomed views").
  int zoom = 24;
  double zoom_run = 0.3;
  int zoom_min_run = 10;
  // View updates code only the MCUs the client reads while the view serves
  // (WalkViewPlan::Update::mcus: region images); false: whole views.
  bool regions = true;
  double tolerance = 0.005;  // share of a frame's pixels that may go without a view within the threshold
  // Occluded views (WalkViewOptions::occlusion_margin, occlusion_updates;
  // a margin over 1: no occlusion test), and the share of a frame's pixels
  // that only occluded views may serve before an update is due. Measured in
  // docs/walkthrough.md ("Occluded views").
  double occlusion_margin = 0.5;
  bool occlusion_updates = true;
  // (0.02 measured best with the test by shares of area, 0.01 with the test per pixel.)
  double occlusion_tolerance = 0.01;
  // The occlusion test per pixel, from the visibility buffers sampled every
  // second pixel each way (WalkViewBuffers, WalkViewOptions::occlusion_share);
  // false: by shares of each polygon's area (occlusion_margin).
  bool pixel_occlusion = true;
  double occlusion_share = 0.1;
  int quality = -1;       // the views' image quality; -1: each view's by the rate control
  // The rate control: the stream is shaped for a link of rate_kbps into a
  // client whose stream window holds buffer_bytes, every frame's data there
  // by its time with a pre-roll of at most preroll_ms (docs/walkthrough.md).
  uint32_t preroll_ms = 1000;
  size_t buffer_bytes = link::device_config(0).channels[link::channel::kStream].rx_bytes;  // the client firmware's
  // A byte reaches the client when the link frame carrying it is whole: up
  // to a frame's time on a line of the stream's rate later (the frames the
  // host sends on such a line: link::line_frame_payload). false: byte by byte.
  bool link_framing = true;
  int width = 240, height = 180;
  int threads = 0;
  std::function<void(const std::string& stage, size_t done, size_t total)> progress;
};

struct WalkEncodeResult {
  std::vector<uint8_t> stream;
  int quality = 0;                // the views' mean quality
  std::vector<int> view_quality;  // each view update's, in stream order
  uint32_t preroll_ms = 0;        // the pre-roll the stream states (WLKP)
  uint32_t rate_bytes = 0, buffer_bytes = 0;
  size_t first_frame_bytes = 0;   // the stream up to the first frame record (header, first views, first geometry)
  std::vector<WalkPiece> pieces;  // the stream as the client takes it (vds/enc/walk_schedule.h)
  size_t view_updates = 0, view_refinements = 0;
  size_t view_predicted = 0;  // view updates coded as a residual against the client's prediction
  size_t view_zoomed = 0;     // view updates of a zoomed view (WalkEncodeOptions::zoom)
  size_t view_mcus = 0, view_mcus_coded = 0;  // the updates' MCUs, and those their images code
  // Bytes by part: header (HEAD, WLKP), views (WVUP and the images), the
  // records' geometry, and the rest of the records (pose, views, framing).
  size_t header_bytes = 0, view_bytes = 0, geometry_bytes = 0, frame_bytes = 0;
  uint32_t slots = 0;
  size_t polygons_sent = 0, polygons_resent = 0;  // the geometry: polygon sends, and those of a polygon sent before (evicted since)
  size_t workspace_bytes = 0;       // what the client needs beyond its chunk buffer
  double kbps = 0;                  // the whole stream over the path's duration
  double psnr_rgb = 0;              // the client's frames against the ground truth, pooled
  std::vector<double> frame_psnr;   // per frame
  std::vector<size_t> bytes_by_frame;  // per frame: the stream bytes it brings (its views and part of its record; the header with frame 0)
  std::vector<uint32_t> frame_crc;  // the CRC of each frame the client displays
  std::vector<io::Image> frames;    // what the client shows (when keep_frames)
};

// The client's pose of a path pose (1/16 unit, 2^-16 turn).
WalkPose walk_pose(const CameraPose& p);
// Back to a path pose (what the client's camera is).
CameraPose from_walk_pose(const WalkPose& p);

// `s` is what the camera sees: the ground truth and the views are drawn
// from it. `geometry`, if given, is what the client draws them onto: a
// scene of the same shape in fewer triangles (walk_geometry_scene), whose
// textures are s's; the visibility the plans work from is its own.
WalkEncodeResult encode_walk(const Scene& s, const CameraPath& path, const WalkEncodeOptions& o, bool keep_frames = false,
                             const Scene* geometry = nullptr);

}  // namespace vds::enc
