// `vds encode-walk SCENE --path PATH --rate KBPS -o OUT.vds`: a walkthrough
// stream (vds/enc/walk_stream.h), played through the client library as it
// is made, with what the client shows measured against the ground truth.
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <memory>
#include <string>

#include "commands.h"
#include "vds/enc/camera_path.h"
#include "vds/enc/scene.h"
#include "vds/enc/scene_shape.h"
#include "vds/enc/stream_writer.h"
#include "vds/enc/walk_stream.h"
#include "vds/io/y4m.h"

namespace vds::cli {
namespace {

// How far the decimated shape may stray from the scene's (docs/walkthrough.md,
// "Fewer triangles").
constexpr double kWalkShapeToleranceM = 1.0 / 16;

struct EncodeWalkOptions {
  std::string scene, path, out, y4m, per_frame, size = "240x180";
  double rate = 16, threshold = 18, widen = -1, view_scale = -1, occlusion = -1, occlusion_tolerance = -1, occlusion_share = -1;
  int min_pixels = -1;
  double shape_tolerance = -1, vertex_tolerance = -1;  // metres
  int lookahead = -1, preroll = -1, window = -1, max_sends = -1, hot_window = -1;
  double zoom_run = -1;
  bool predict = false, keep_triangles = false, no_occlusion_updates = false, whole_views = false, area_occlusion = false;
  int views = 2, zoom = -1, zoom_min_run = -1, quality = -1, refine_delta = -1, refine_after = -1, frames_per_record = kWalkMaxFramesPerRecord;
};

void run_encode_walk(const EncodeWalkOptions& o) {
  const enc::Scene scene = enc::load_scene(o.scene);
  // What the client draws the views onto: the same shape in fewer
  // triangles (docs/walkthrough.md, "Fewer triangles").
  std::unique_ptr<enc::Scene> drawn;
  if (!o.keep_triangles) {
    enc::ShapeStats st;
    enc::ShapeOptions so;
    so.tolerance = (o.shape_tolerance >= 0 ? o.shape_tolerance : kWalkShapeToleranceM) / scene.metres_per_unit;
    drawn = std::make_unique<enc::Scene>(enc::simplify_shape(scene, so, &st));
    std::fprintf(stderr, "encode-walk: the client draws %zu triangles for the scene's %zu (%zu regions in one plane drawn as their outline; "
                 "%zu triangles decimated to %zu)\n",
                 st.triangles_out, scene.triangles(), st.merged, st.decimated_in, st.decimated_out);
  }
  const std::vector<uint8_t> text = enc::read_file(o.path);
  const enc::CameraPath path = enc::read_camera_path(std::string(text.begin(), text.end()), o.path);
  if (path.frames.empty()) throw Failure(kExitBadInput, o.path + ": no frames");
  enc::WalkEncodeOptions wo;
  wo.rate_kbps = o.rate;
  wo.views = o.views;
  wo.threshold = o.threshold;
  wo.quality = o.quality;
  wo.frames_per_record = o.frames_per_record;
  if (o.hot_window >= 0) wo.window = o.hot_window;
  wo.predict = o.predict;
  wo.regions = !o.whole_views;
  if (o.zoom >= 0) wo.zoom = o.zoom;
  if (o.zoom_min_run >= 0) wo.zoom_min_run = o.zoom_min_run;
  if (o.zoom_run >= 0) wo.zoom_run = o.zoom_run;
  if (o.vertex_tolerance >= 0) wo.vertex_tolerance_m = o.vertex_tolerance;
  if (o.preroll >= 0) wo.preroll_ms = static_cast<uint32_t>(o.preroll);
  if (o.window >= 0) wo.buffer_bytes = static_cast<size_t>(o.window);
  if (o.max_sends >= 0) wo.max_sends = o.max_sends;
  if (o.lookahead >= 0) wo.lookahead = o.lookahead;
  if (o.widen > 0) wo.view_widen = o.widen;
  if (o.occlusion >= 0) wo.occlusion_margin = o.occlusion;
  if (o.no_occlusion_updates) wo.occlusion_updates = false;
  if (o.occlusion_tolerance >= 0) wo.occlusion_tolerance = o.occlusion_tolerance;
  if (o.occlusion_share >= 0) wo.occlusion_share = o.occlusion_share;
  if (o.area_occlusion) wo.pixel_occlusion = false;
  if (o.min_pixels >= 0) wo.min_pixels = static_cast<uint32_t>(o.min_pixels);
  if (o.view_scale > 0) wo.view_scale = o.view_scale;
  if (o.refine_delta >= 0) wo.refine_delta = o.refine_delta;
  if (o.refine_after >= 0) wo.refine_after = o.refine_after;
  if (std::sscanf(o.size.c_str(), "%dx%d", &wo.width, &wo.height) != 2 || wo.width < 16 || wo.height < 16 || wo.width > 1024 ||
      wo.height > 1024)
    throw Failure(kExitUsage, "--size must be WIDTHxHEIGHT, each 16..1024, not '" + o.size + "'");
  std::string last;
  wo.progress = [&](const std::string& stage, size_t done, size_t total) {
    std::fprintf(stderr, "\rencode-walk: %s %zu/%zu   ", stage.c_str(), done, total);
    if (done == total) std::fprintf(stderr, "\n");
    std::fflush(stderr);
  };
  const enc::WalkEncodeResult r = enc::encode_walk(scene, path, wo, !o.y4m.empty(), drawn.get());
  enc::write_file(o.out, r.stream);
  if (!o.y4m.empty()) {
    io::Y4mWriter y(o.y4m, static_cast<int>(std::lround(path.fps)));
    for (const io::Image& f : r.frames) y.write(f);
    y.close();
  }
  if (!o.per_frame.empty()) {
    std::string csv = "frame,bytes,psnr_rgb\n";
    for (size_t f = 0; f < r.bytes_by_frame.size(); ++f)
      csv += std::to_string(f) + "," + std::to_string(r.bytes_by_frame[f]) + "," + std::to_string(r.frame_psnr[f]) + "\n";
    enc::write_file(o.per_frame, std::vector<uint8_t>(csv.begin(), csv.end()));
  }
  const double secs = path.frames.size() / path.fps;
  int qmin = 100, qmax = 0;
  for (int q : r.view_quality) qmin = std::min(qmin, q), qmax = std::max(qmax, q);
  if (r.view_quality.empty()) qmin = qmax = 0;
  std::printf("%s: %zu frames (%.1f s), %zu bytes = %.2f kbit/s (target %.2f): header %zu, views %zu (%zu updates at quality %d to %d, "
              "mean %d, %zu of them zoomed, %zu residuals against the client's prediction, %zu refinements; %zu of their %zu MCUs coded), "
              "geometry %zu, frames %zu\n",
              o.out.c_str(), path.frames.size(), secs, r.stream.size(), r.kbps, o.rate, r.header_bytes, r.view_bytes,
              r.view_updates, qmin, qmax, r.quality, r.view_zoomed, r.view_predicted, r.view_refinements, r.view_mcus_coded, r.view_mcus,
              r.geometry_bytes, r.frame_bytes);
  if (r.rate_bytes != 0)
    std::printf("  schedule: pre-roll %.3f s at %u bytes/s into a %u-byte window: every frame's data arrives by its time; "
                "the first frame's data %zu bytes\n",
                r.preroll_ms / 1000.0, r.rate_bytes, r.buffer_bytes, r.first_frame_bytes);
  else
    std::printf("  schedule: none (untimed: the client shows each frame when its data is whole); the first frame's data %zu bytes\n",
                r.first_frame_bytes);
  if (r.rate_bytes == 0)
    std::fprintf(stderr, "encode-walk: warning: at %.2f kbit/s no pre-roll brings every frame in time%s (what follows a frame "
                 "record must fit the client's %zu-byte window): the stream is untimed\n",
                 o.rate, o.quality >= 0 ? " at this quality" : " even at the lowest quality",
                 o.window >= 0 ? static_cast<size_t>(o.window) : enc::WalkEncodeOptions{}.buffer_bytes);
  if (r.preroll_ms > (o.preroll >= 0 ? static_cast<uint32_t>(o.preroll) : enc::WalkEncodeOptions{}.preroll_ms))
    std::fprintf(stderr, "encode-walk: warning: the stream needs a pre-roll of %.3f s, more than asked\n", r.preroll_ms / 1000.0);
  double worst = 99;
  for (double p : r.frame_psnr) worst = std::min(worst, p);
  std::printf("  client: %u triangle slots, %d views, %zu bytes of workspace; PSNR R,G,B %.2f dB pooled, %.2f dB worst frame\n",
              r.slots, o.views, r.workspace_bytes, r.psnr_rgb, worst);
  std::printf("  geometry: %zu polygon sends, %zu of them of a polygon evicted since it was sent before\n", r.polygons_sent, r.polygons_resent);
}

}  // namespace

void add_encode_walk(CLI::App& app) {
  auto o = std::make_shared<EncodeWalkOptions>();
  CLI::App* sub = app.add_subcommand("encode-walk", "Encode a walkthrough of a scene along a camera path (docs/walkthrough.md)");
  sub->add_option("scene", o->scene, "A .bsp, .gltf, .glb or .obj file, or an OpenArena map name")->required();
  sub->add_option("--path", o->path, "Camera path: 'frame x y z yaw_deg pitch_deg' per line")->required();
  sub->add_option("-o,--output", o->out, "Stream to write")->required();
  sub->add_option("--rate", o->rate, "Target rate, kbit/s (default 16)")->check(kPositive);
  sub->add_option("--views", o->views, "Views the client holds (default 2)")->check(CLI::Range(1, 8));
  sub->add_option("--threshold", o->threshold, "Largest magnification a view serves (default 18)")->check(kPositive);
  sub->add_option("--preroll", o->preroll, "Most pre-roll, ms: every frame's data arrives by its time (default 1000)")
      ->check(CLI::Range(0, static_cast<int>(kWalkMaxPrerollMs)));
  sub->add_option("--max-sends", o->max_sends, "Polygons a frame sends at most; the rest go earlier where their slots allow (0: no limit)")
      ->check(CLI::Range(0, 100000));
  sub->add_option("--hot-window", o->hot_window,
                  "A triangle is drawn in the frames within this many either side of those it shows in (default 2)")
      ->check(CLI::Range(0, 60));
  sub->add_option("--window", o->window, "The client's stream window, bytes (default 4096: the client firmware's)")
      ->check(CLI::Range(256, 1 << 24));
  sub->add_option("--quality", o->quality, "The views' image quality (default: each view's, by the rate control)")->check(CLI::Range(0, 100));
  sub->add_option("--frames-per-record", o->frames_per_record, "Most frames a WFRM record holds (default 8)")
      ->check(CLI::Range(1, static_cast<int>(kWalkMaxFramesPerRecord)));
  sub->add_flag("--predict", o->predict, "View updates may be residuals against the client's prediction of the view");
  sub->add_option("--zoom", o->zoom,
                  "Zoomed view updates: a view whose focal length is the views' times Z / 16 where it serves long enough (16: none)")
      ->check(CLI::Range(16, 64));
  sub->add_option("--zoom-run", o->zoom_run, "A zoomed view serves at least this share of the frames the unzoomed one would")
      ->check(CLI::Range(0.0, 1.0));
  sub->add_option("--zoom-min-run", o->zoom_min_run, "... and at least this many frames")->check(CLI::Range(1, 1000));
  sub->add_flag("--whole-views", o->whole_views, "View updates code the whole view, not only the MCUs the client reads while it serves");
  sub->add_option("--lookahead", o->lookahead, "Frames ahead a view's camera may come from (default 20)")->check(CLI::Range(0, 200));
  sub->add_option("--widen", o->widen, "tan(half the views' field of view) / tan(half the screen's) (default 1.5)")
      ->check(CLI::Range(1.0, 4.0));
  sub->add_option("--view-scale", o->view_scale, "The views' size over the frame's, each side (default 2/3)")->check(CLI::Range(0.1, 1.0));
  sub->add_option("--occlusion-share", o->occlusion_share,
                  "A view that sees something else in front of more than this share of a polygon's pixels on the screen is "
                  "occluded for it: another view draws it if one serves it (default 0.1)")
      ->check(CLI::Range(0.0, 1.0));
  sub->add_flag("--area-occlusion", o->area_occlusion,
                "Tell occluded views by the share of each polygon's area they see (--occlusion-margin), not pixel by pixel");
  sub->add_option("--occlusion-margin", o->occlusion,
                  "With --area-occlusion: a view seeing this much less of a polygon than the screen does (share of its area) "
                  "is occluded for it (default 0.5; over 1: no such test)")
      ->check(CLI::Range(0.0, 2.0));
  sub->add_option("--occlusion-tolerance", o->occlusion_tolerance,
                  "The share of a frame's pixels that occluded views may hide before a view update (default 0.01; "
                  "with --area-occlusion: that only occluded views serve, 0.02 measured best there)")
      ->check(CLI::Range(0.0, 1.0));
  sub->add_option("--min-pixels", o->min_pixels,
                  "A triangle covering fewer of a frame's pixels than this is not drawn there where a larger one "
                  "the frame shows lies behind it (default 16; 0: every triangle a frame shows is drawn)")
      ->check(CLI::Range(0, 1000));
  sub->add_flag("--no-occlusion-updates", o->no_occlusion_updates,
                "No view updates for occluded views (they only lose to views that are not occluded)");
  sub->add_flag("--keep-triangles", o->keep_triangles,
                "The client draws the views onto the scene's own triangles (default: neighbours in one plane merged, "
                "surfaces decimated)");
  sub->add_option("--shape-tolerance", o->shape_tolerance,
                  "Metres the shape the views are drawn onto may move from the scene's when it is decimated (default " +
                      std::to_string(kWalkShapeToleranceM) + "; 0: not decimated)")
      ->check(CLI::Range(0.0, 10.0));
  sub->add_option("--vertex-tolerance", o->vertex_tolerance,
                  "Metres a vertex may move to the coarsest power-of-two grid the geometry is sent on (default " +
                      std::to_string(enc::WalkEncodeOptions{}.vertex_tolerance_m) + ")")
      ->check(CLI::Range(0.0, 10.0));
  sub->add_option("--y4m", o->y4m, "Also write what the client shows as Y4M");
  sub->add_option("--per-frame", o->per_frame, "Also write each frame's stream bytes and PSNR R,G,B as CSV");
  sub->add_option("--size", o->size, "Frame size WIDTHxHEIGHT (default 240x180)");
  sub->add_option("--refine-delta", o->refine_delta, "A refinement's image quality above the views' (0: none)")->check(CLI::Range(0, 100));
  sub->add_option("--refine-after", o->refine_after, "Frames after a view arrives that it is refined")->check(CLI::Range(1, 1000));
  sub->callback([o] { run_encode_walk(*o); });
}

}  // namespace vds::cli
