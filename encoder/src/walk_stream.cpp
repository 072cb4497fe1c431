// vds encoder: walkthrough streams (vds/enc/walk_stream.h).
#include "vds/enc/walk_stream.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <map>
#include <numeric>
#include <queue>
#include <stdexcept>

#include "vds/enc/arith_encoder.h"
#include "vds/enc/frames.h"
#include "vds/enc/image_codec.h"
#include "vds/enc/stream_writer.h"
#include "vds/enc/walk_geometry.h"
#include "vds/enc/walk_schedule.h"
#include "vds/enc/walk_views.h"
#include "vds/player.h"

namespace vds::enc {

namespace {

constexpr double kTurn = 65536.0 / 360.0;

// The WFRM records, mirroring the client's WalkFrameDecoder.
class WalkFrameEncoder {
 public:
  WalkFrameEncoder() { state_.reset(); }
  // A record's frame count, first in its coder.
  void encode_count(ArithEncoder& e, uint32_t frames, uint8_t max_frames) {
    e.encode_unary(state_.record_frames, kWalkMaxFramesPerRecord - 1, frames - 1, max_frames - 1u);
  }
  // `view_of` holds each slot's last view (in) and is set to `views_now`
  // for the hot slots (out); `fresh`: the view slots updated since the
  // frame before.
  void encode(ArithEncoder& e, const WalkPose& pose, const std::vector<uint32_t>& hot, const std::vector<uint8_t>& views_now,
              std::vector<uint8_t>& view_of, const std::vector<bool>& fresh, uint8_t views) {
    int32_t pred[5], steps[5];
    state_.predict(pred);
    walk_pose_to_steps(pose, steps);
    for (int k = 0; k < 5; ++k) {
      int32_t r = steps[k] - pred[k];
      if (k >= 3) r = static_cast<int16_t>(static_cast<uint16_t>(r));  // angles: the short way round
      e.encode_signed(state_.zero[k], state_.mag[k], 6, r, 6, 3);
    }
    const int other_bits = walk_other_view_bits(views);
    if (stamp_.size() < view_of.size()) stamp_.resize(view_of.size(), 0);
    const uint16_t now = walk_frame_stamp(state_.frames);
    int kept = 1;
    for (size_t i = 0; i < hot.size(); ++i) {
      uint8_t& v = view_of[hot[i]];
      if (v >= views) v = 0;
      const uint8_t want = views_now[i];
      if (views > 1) {
        const int ctx = walk_view_context(stamp_[hot[i]], state_.frames, fresh[v], kept);
        kept = want == v ? 1 : 0;
        e.encode_bit(state_.same_view[ctx], kept);
        if (want != v) e.encode_bits_bypass(want > v ? want - 1u : want, other_bits);
      }
      v = want;
      stamp_[hot[i]] = now;
    }
    state_.push(steps);
  }

 private:
  WalkFrameState state_{};
  std::vector<uint16_t> stamp_;  // per slot, as the client keeps them
};

// The client, fed the stream as it is written: what its view slots hold
// when a view update's image is coded (the prediction it drew, or the view
// a refinement adds to).
class MirrorClient {
 public:
  explicit MirrorClient(size_t workspace) : ws_(workspace + (1u << 22)), arena_(ws_.data(), ws_.size()) {
    PlayerConfig cfg = kClientPlayerConfig;
    cfg.max_chunk_bytes = 1u << 21;
    if (player_.init(arena_, cfg, PlayerCallbacks{}) != Status::ok) throw std::logic_error("encode_walk: the client cannot start");
  }
  void feed(const StreamWriter& w) {
    const auto b = w.bytes();
    const Status s = player_.feed(b.data() + fed_, b.size() - fed_);
    fed_ = b.size();
    if (s != Status::more_input)
      throw std::logic_error(std::string("encode_walk: the client refused the stream: ") + status_name(s) + " (" +
                             player_.error_detail() + ")");
  }
  bool predicted() const { return player_.walk_view_predicted(); }
  Planes slot(uint8_t v) const {
    const Texture* t = player_.walk_view(v);
    if (t == nullptr) throw std::logic_error("encode_walk: no such view slot");
    Planes p(t->width, t->height, ChromaFormat::yuv420);
    for (int c = 0; c < 3; ++c) {
      const uint8_t* src = c == 0 ? static_cast<const uint8_t*>(t->texels) : (c == 1 ? t->cb : t->cr);
      const size_t stride = c == 0 ? t->stride : t->chroma_stride;
      for (int y = 0; y < p.plane_height(c); ++y)
        std::copy_n(src + y * stride, p.plane_width(c), p.row(c, y));
    }
    return p;
  }

 private:
  std::vector<uint8_t> ws_;
  Arena arena_;
  Player player_;
  size_t fed_ = 0;
};

}  // namespace

WalkPose walk_pose(const CameraPose& p) {
  WalkPose w;
  const auto step = [](double v) {
    const double r = std::round(v * 16);
    if (!(std::fabs(r) < (1 << 19))) throw std::runtime_error("a camera position outside the client's range: " + std::to_string(v));
    return Q16_16::from_raw(static_cast<int32_t>(r) * (1 << kWalkPoseShift));
  };
  w.position = {step(p.x), step(p.y), step(p.z)};
  w.yaw = static_cast<uint16_t>(static_cast<int64_t>(std::llround(p.yaw_deg * kTurn)) & 0xFFFF);
  w.pitch = static_cast<uint16_t>(static_cast<int64_t>(std::llround(p.pitch_deg * kTurn)) & 0xFFFF);
  return w;
}

CameraPose from_walk_pose(const WalkPose& w) {
  CameraPose p;
  p.x = w.position.x.raw() / 65536.0;
  p.y = w.position.y.raw() / 65536.0;
  p.z = w.position.z.raw() / 65536.0;
  p.yaw_deg = w.yaw / kTurn;
  p.pitch_deg = static_cast<int16_t>(w.pitch) / kTurn;
  return p;
}

WalkEncodeResult encode_walk(const Scene& s, const CameraPath& path, const WalkEncodeOptions& o, bool keep_frames,
                             const Scene* geometry) {
  const Scene& drawn = geometry ? *geometry : s;  // what the client draws
  if (drawn.textures.size() != s.textures.size())
    throw std::invalid_argument("encode_walk: the geometry scene's textures are not the scene's");
  const size_t n = path.frames.size();
  if (n == 0) throw std::invalid_argument("encode_walk: an empty path");
  if (o.views < 1 || o.views > kWalkMaxViews) throw std::invalid_argument("encode_walk: 1 to 8 views");
  const auto progress = [&](const std::string& stage, size_t done, size_t total) {
    if (o.progress) o.progress(stage, done, total);
  };
  // 1. Ground truth: the frames and what each shows.
  RenderOptions ro;
  ro.width = o.width;
  ro.height = o.height;
  const std::vector<io::Image> images = load_scene_images(s);
  // What the client draws: a frame leaves out small triangles where that
  // opens no hole (the second ID buffer of the visibility the plans use).
  RenderOptions truth_ro = ro;
  truth_ro.min_pixels = geometry ? 0 : o.min_pixels;
  const SceneRenderer renderer(s, images, truth_ro);
  const SceneCamera sc = scene_camera(path.frames[0], path.hfov_deg, o.width, o.height);  // the screen's intrinsics
  // The views' size.
  if (!(o.view_scale > 0 && o.view_scale <= 1)) throw std::invalid_argument("encode_walk: a view scale in (0, 1]");
  // (No smaller than the client's smallest focal length allows.)
  const double scale = std::clamp(o.view_scale, std::min(1.0, kCameraMinFocalPx / sc.focal), 1.0);
  const int view_w = std::min(o.width, std::max(16, static_cast<int>(std::ceil(o.width * scale / 2 - 1e-9)) * 2));
  const int view_h = std::min(o.height, std::max(16, static_cast<int>(std::ceil(o.height * scale / 2 - 1e-9)) * 2));
  std::vector<io::Image> truth(n);
  std::vector<std::vector<std::pair<uint32_t, uint32_t>>> visible(n);
  // The visibility buffers for the per-pixel occlusion test, every second
  // pixel each way (WalkViewBuffers): what the client draws at each.
  WalkViewBuffers buffers;
  buffers.step = 2;
  buffers.width = (o.width + 1) / 2;
  buffers.height = (o.height + 1) / 2;
  if (o.pixel_occlusion) {
    buffers.screen_ids.resize(n);
    buffers.view_ids.resize(n);
    buffers.view_depth.resize(n);
  }
  // What the client draws at each pixel (drawn_triangle_ids): the
  // triangles the frame shows, and the screen's buffer for the per-pixel
  // occlusion test.
  const auto keep_visibility = [&](size_t f, const SceneFrame& fr) {
    const std::vector<uint32_t> drawn_ids = drawn_triangle_ids(fr);
    visible[f] = triangle_pixels(drawn_ids);
    if (o.pixel_occlusion) buffers.screen_ids[f] = walk_buffer_samples(drawn_ids, o.width, o.height, buffers.step);
  };
  render_path(renderer, path, o.threads, [&](size_t f, const SceneFrame& fr) {
    truth[f] = fr.rgb;
    if (!geometry) keep_visibility(f, fr);
  }, [&](size_t done) { progress("ground truth", done, n); });
  RenderOptions vro = ro;
  vro.supersample = 1;
  vro.max_aniso = 1;
  if (geometry) {
    // What the client's triangles show, pixel by pixel (the alpha-tested
    // ones cut out as the scene's are).
    RenderOptions ids_ro = vro;
    ids_ro.min_pixels = o.min_pixels;
    const SceneRenderer ids(drawn, images, ids_ro);
    render_path(ids, path, o.threads, keep_visibility, [&](size_t done) { progress("visibility", done, n); });
  }
  // 2. Geometry and views.
  std::vector<std::vector<uint32_t>> ids(n);
  for (size_t f = 0; f < n; ++f)
    for (const auto& [id, px] : visible[f]) ids[f].push_back(id);
  const WalkGeometryPlan probe = plan_walk_geometry(ids, kWalkMaxSlots, o.window);
  const uint32_t slots = static_cast<uint32_t>(std::min<size_t>(kWalkMaxSlots, probe.peak_hot + 16));
  const WalkGeometryPlan geo = plan_walk_geometry(ids, slots, o.window, static_cast<size_t>(o.max_sends));
  WalkViewOptions vo;
  vo.slots = o.views;
  vo.threshold = o.threshold;
  vo.lookahead = o.lookahead;
  vo.tolerance_px = static_cast<size_t>(o.tolerance * o.width * o.height);
  vo.occlusion_margin = o.occlusion_margin;
  vo.occlusion_updates = o.occlusion_updates;
  vo.occlusion_tolerance_px = static_cast<size_t>(o.occlusion_tolerance * o.width * o.height);
  vo.zoom = o.zoom;
  vo.zoom_run = o.zoom_run;
  vo.zoom_min_run = o.zoom_min_run;
  vo.width = o.width;
  vo.height = o.height;
  // Views see wider than the screen (a pan stays inside a view longer):
  // what a view at each frame's camera shows.
  // (No wider than the client's smallest focal length allows.)
  const double widen = std::clamp(o.view_widen, 1.0, std::max(1.0, sc.focal * view_w / o.width / kCameraMinFocalPx));
  const double view_hfov = scaled_hfov(path.hfov_deg, widen);
  vo.view_hfov_deg = view_hfov;
  vo.view_width = view_w;
  vo.view_height = view_h;
  CameraPath wide = path;
  wide.hfov_deg = view_hfov;
  // (Alpha-tested surfaces cut out as the scene's are: what lies behind a
  // grating shows through it.)
  const SceneRenderer view_vis(drawn, images, vro);
  std::vector<std::vector<std::pair<uint32_t, uint32_t>>> view_visible(n);
  render_path(view_vis, wide, o.threads, [&](size_t f, const SceneFrame& fr) {
    view_visible[f] = visible_triangles(fr);
    if (o.pixel_occlusion) {
      buffers.view_ids[f] = walk_buffer_samples(fr.ids, o.width, o.height, buffers.step);
      buffers.view_depth[f] = walk_buffer_samples(fr.depth, o.width, o.height, buffers.step);
    }
  }, [&](size_t done) { progress("view visibility", done, n); });
  vo.occlusion_share = o.occlusion_share;
  const WalkViewPlan vp = plan_walk_views(drawn, path, visible, vo, &view_visible, o.pixel_occlusion ? &buffers : nullptr);
  // 3. The views, rendered at the client's cameras.
  std::vector<WalkPose> poses(n);
  for (size_t f = 0; f < n; ++f) poses[f] = walk_pose(path.frames[f]);
  // A view's camera is named by an index: frame g at the views' own focal
  // length is g, zoomed n + g (WalkViewOptions::zoom).
  const auto camera_of = [&](const WalkViewPlan::Update& u) {
    return u.camera_frame + (u.zoom != kWalkZoomUnit ? static_cast<uint32_t>(n) : 0u);
  };
  const auto frame_of = [&](uint32_t j) { return j % static_cast<uint32_t>(n); };
  const auto zoom_of = [&](uint32_t j) { return j >= n ? static_cast<uint8_t>(o.zoom) : kWalkZoomUnit; };
  const auto wvup_bytes = [&](uint32_t j) -> size_t { return zoom_of(j) != kWalkZoomUnit ? kWalkViewMaxBytes : kWalkViewBytes; };
  // (As Y'CbCr planes, the form the image codec takes.)
  std::map<uint32_t, Planes> view_planes;
  for (const auto& ups : vp.updates)
    for (const auto& u : ups) view_planes[camera_of(u)];
  size_t done = 0;
  RenderOptions view_ro = ro;
  view_ro.width = view_w;
  view_ro.height = view_h;
  const SceneRenderer view_renderer(s, images, view_ro);
  const double zoomed_hfov = scaled_hfov(view_hfov, static_cast<double>(kWalkZoomUnit) / o.zoom);
  for (auto& [j, planes] : view_planes) {
    planes = rgb_to_planes(view_renderer.render(from_walk_pose(poses[frame_of(j)]), j >= n ? zoomed_hfov : view_hfov).rgb,
                           ChromaFormat::yuv420);
    progress("views", ++done, view_planes.size());
  }
  // 4. The header and the parts that do not depend on the views' quality.
  StreamHeader h = default_header(StreamMode::walkthrough, static_cast<uint16_t>(o.width), static_cast<uint16_t>(o.height));
  h.frame_period_us = static_cast<uint32_t>(std::lround(1e6 / path.fps));
  h.frame_count = static_cast<uint32_t>(n);
  h.focal_x_q16 = h.focal_y_q16 = static_cast<int32_t>(std::lround(sc.focal * 65536));
  h.center_x_q16 = static_cast<int32_t>(std::lround(sc.cx * 65536));
  h.center_y_q16 = static_cast<int32_t>(std::lround(sc.cy * 65536));
  const double near = 1.0 / 32 / s.metres_per_unit;
  h.near_q16 = static_cast<int32_t>(std::lround(near * 65536));
  h.far_q16 = h.near_q16 * 4096;
  WalkParams wp;
  wp.slots = static_cast<uint16_t>(slots);
  wp.views = static_cast<uint8_t>(o.views);
  if (o.frames_per_record < 1 || o.frames_per_record > kWalkMaxFramesPerRecord)
    throw std::invalid_argument("encode_walk: 1 to 8 frames a record");
  wp.frames_per_record = static_cast<uint8_t>(o.frames_per_record);
  wp.quantum_raw = choose_walk_quantum(drawn, o.vertex_tolerance_m / s.metres_per_unit);
  wp.view_focal_q16 = static_cast<int32_t>(std::lround(scene_camera(path.frames[0], view_hfov, view_w, view_h).focal * 65536));
  wp.view_width = static_cast<uint16_t>(view_w);
  wp.view_height = static_cast<uint16_t>(view_h);
  h.workspace_bytes = static_cast<uint32_t>(Player::walk_workspace_bytes(h, wp, kClientPlayerConfig));
  h.max_triangles = slots;
  // The view updates, numbered in stream order; each has its own quality
  // and the MCUs its image codes (none left out: a whole view).
  std::vector<std::vector<size_t>> update_of(n);
  std::vector<uint32_t> update_camera;
  std::vector<std::vector<uint8_t>> update_region;
  for (size_t f = 0; f < n; ++f)
    for (const auto& u : vp.updates[f]) {
      update_of[f].push_back(update_camera.size());
      update_camera.push_back(camera_of(u));
      const bool whole = !o.regions || std::all_of(u.mcus.begin(), u.mcus.end(), [](uint8_t m) { return m != 0; });
      update_region.push_back(whole ? std::vector<uint8_t>{} : u.mcus);
    }
  // Refinements: a view that serves at least 2 * refine_after frames gets,
  // refine_after frames after it arrives, a residual image at a higher
  // quality against what the client holds of it.
  struct Refine {
    uint32_t slot, camera;  // camera: as update_camera names it
    size_t update;  // the update it refines
  };
  std::vector<std::vector<Refine>> refines(n);
  if (o.refine_delta > 0) {
    for (size_t f = 0; f < n; ++f)
      for (size_t k = 0; k < vp.updates[f].size(); ++k) {
        const auto& u = vp.updates[f][k];
        size_t next = n;
        for (size_t g = f + 1; g < n && next == n; ++g)
          for (const auto& v : vp.updates[g])
            if (v.slot == u.slot) next = g;
        const size_t at = f + static_cast<size_t>(o.refine_after);
        if (next - f >= 2 * static_cast<size_t>(o.refine_after) && at < n)
          refines[at].push_back({u.slot, camera_of(u), update_of[f][k]});
      }
  }
  // Records: a frame with view updates or refinements starts one (they
  // must arrive before it, and after every frame the record before it
  // draws); a record holds up to frames_per_record frames.
  std::vector<size_t> record_start;
  for (size_t f = 0; f < n; ++f)
    if (f == 0 || !vp.updates[f].empty() || !refines[f].empty() ||
        f - record_start.back() >= static_cast<size_t>(wp.frames_per_record))
      record_start.push_back(f);
  // The frame after record r's last.
  const auto record_end = [&](size_t r) { return r + 1 < record_start.size() ? record_start[r + 1] : n; };
  WalkGeometryEncoder ge(slots, wp.quantum_raw);
  WalkFrameEncoder fe;
  std::vector<std::vector<uint8_t>> wfrm(record_start.size());  // by record
  std::vector<size_t> geometry_part(record_start.size());       // bytes of each record's geometry
  std::vector<size_t> frame_share(n);  // each frame's part of its record (the first's with the frame count)
  std::vector<uint8_t> view_of(slots, 0);
  std::vector<uint8_t> slot_view(slots, 0);
  std::vector<uint32_t> id_of_slot(slots, 0);  // the triangle each slot holds, as the sends so far put them
  for (size_t r = 0; r < record_start.size(); ++r) {
    const size_t end = record_end(r);
    ArithEncoder e;
    fe.encode_count(e, static_cast<uint32_t>(end - record_start[r]), wp.frames_per_record);
    for (size_t f = record_start[r]; f < end; ++f) {
      std::vector<WalkGeometryEncoder::Send> sends;
      for (const auto& snd : geo.sends[f]) {
        WalkGeometryEncoder::Send gs{snd.slot, snd.hot, {}};
        for (int c = 0; c < 3; ++c)
          for (int a = 0; a < 3; ++a)
            gs.vertices[static_cast<size_t>(c)][static_cast<size_t>(a)] =
                drawn.vertices[drawn.indices[3 * static_cast<size_t>(snd.id) + static_cast<size_t>(c)]].pos[static_cast<size_t>(a)];
        sends.push_back(gs);
      }
      const size_t g0 = e.finished_size();
      ge.encode(e, sends, geo.hot[f]);
      geometry_part[r] += e.finished_size() - g0;
      // Each hot triangle's view: the plan's for those the frame shows, else the one it had.
      std::map<uint32_t, int8_t> choice;
      for (size_t k = 0; k < visible[f].size(); ++k) choice[visible[f][k].first] = vp.choice[f][k];
      for (const auto& snd : geo.sends[f]) id_of_slot[snd.slot] = snd.id;
      std::vector<uint8_t> now;
      for (uint32_t slot : geo.hot[f]) {
        const auto it = choice.find(id_of_slot[slot]);
        now.push_back(it != choice.end() && it->second >= 0 ? static_cast<uint8_t>(it->second) : slot_view[slot]);
        slot_view[slot] = now.back();
      }
      std::vector<bool> fresh(wp.views, false);  // the WVUPs the client reads before this frame
      for (const auto& u : vp.updates[f]) fresh[u.slot] = true;
      for (const Refine& rf : refines[f]) fresh[rf.slot] = true;
      const size_t before = f == record_start[r] ? 0 : e.finished_size();
      fe.encode(e, poses[f], geo.hot[f], now, view_of, fresh, wp.views);
      frame_share[f] = e.finished_size() - before;
      progress("geometry", f + 1, n);
    }
    wfrm[r] = e.finish();
  }
  // 5. The views' qualities under the rate control, then the stream.
  // A view image's options: its quality, the MCUs it codes (none: all),
  // chunks of at most kViewChunkPayload bytes.
  constexpr uint32_t kViewChunkPayload = 4096;
  const auto view_options = [&](int q, const std::vector<uint8_t>& region) {
    ImageEncodeOptions io;
    io.quality = q;
    io.max_chunk_payload = kViewChunkPayload;
    io.region = region;
    return io;
  };
  // Each view's intra image at a quality, coded once.
  std::map<std::pair<uint32_t, int>, EncodedImage> coded;
  const auto intra = [&](uint32_t g, int q) -> const EncodedImage& {
    auto it = coded.find({g, q});
    if (it == coded.end()) it = coded.emplace(std::make_pair(g, q), encode_planes(view_planes.at(g), view_options(q, {}))).first;
    return it->second;
  };
  // Update u's image at a quality: the view, or its region.
  std::map<std::pair<size_t, int>, EncodedImage> coded_region;
  const auto update_image = [&](size_t u, int q) -> const EncodedImage& {
    if (update_region[u].empty()) return intra(update_camera[u], q);
    auto it = coded_region.find({u, q});
    if (it == coded_region.end()) {
      const ImageEncodeOptions io = view_options(q, update_region[u]);
      it = coded_region.emplace(std::make_pair(u, q), encode_planes(view_planes.at(update_camera[u]), io)).first;
    }
    return it->second;
  };
  StreamHeader hh = h;
  hh.max_chunk_payload = kViewChunkPayload;
  for (const auto& rec : wfrm) hh.max_chunk_payload = std::max<uint32_t>(hh.max_chunk_payload, static_cast<uint32_t>(rec.size()));
  constexpr size_t kFraming = kChunkHeadBytes + kChunkTailBytes;
  size_t header_bytes = 0;
  {
    StreamWriter w(hh);
    uint8_t params[kWalkParamsBytes] = {};
    w.add_chunk(chunk::kWalkParams, params);
    header_bytes = w.size();
  }
  const auto link_latency = [&](double rate) {
    if (!o.link_framing) return 0.0;
    const uint16_t payload = link::line_frame_payload(static_cast<uint32_t>(rate), link::host_config(0).max_tx_payload);
    return link::frame_wire_bound(payload) / rate;
  };
  WalkLink lk;
  lk.rate_bytes = o.rate_kbps * 1000 / 8;
  lk.buffer_bytes = o.buffer_bytes;
  lk.frame_period_s = 1 / path.fps;
  lk.latency_s = link_latency(lk.rate_bytes);
  if (!(lk.rate_bytes >= 1 && lk.rate_bytes < 4e9)) throw std::invalid_argument("encode_walk: a rate of 8 bit/s up to 32 Gbit/s");
  wp.rate_bytes = static_cast<uint32_t>(std::lround(lk.rate_bytes));
  wp.buffer_bytes = static_cast<uint32_t>(std::min<size_t>(o.buffer_bytes, UINT32_MAX));
  // The stream as the client takes it, with the views at qualities `q`
  // (refinements and predicted updates counted as their intra image).
  const auto pieces_at = [&](const std::vector<int>& q) {
    std::vector<WalkPiece> p{{header_bytes, 0, 0, false}};
    for (size_t r = 0; r < record_start.size(); ++r) {
      const uint32_t f = static_cast<uint32_t>(record_start[r]);
      const uint32_t last = static_cast<uint32_t>(record_end(r) - 1);
      for (size_t u : update_of[f]) p.push_back({kFraming + wvup_bytes(update_camera[u]) + update_image(u, q[u]).coded_bytes(), f, f, false});
      for (const Refine& rf : refines[f])
        p.push_back({kFraming + wvup_bytes(rf.camera) + intra(rf.camera, std::min(100, q[rf.update] + o.refine_delta)).coded_bytes(), f, f, false});
      p.push_back({kFraming + wfrm[r].size(), f, last, true});
    }
    return p;
  };
  // The stream with the views at qualities `q`, its stated pre-roll
  // `preroll_ms`; the pieces as written.
  std::vector<WalkPiece> written;
  const auto build = [&](const std::vector<int>& q, uint32_t preroll_ms, WalkEncodeResult* res) {
    StreamWriter w(hh);
    MirrorClient client(h.workspace_bytes);
    WalkParams wpp = wp;
    wpp.preroll_ms = preroll_ms;
    uint8_t params[kWalkParamsBytes];
    walk_params_to_bytes(wpp, params);
    w.add_chunk(chunk::kWalkParams, params);
    client.feed(w);
    res->header_bytes = w.size();
    written.assign(1, WalkPiece{w.size(), 0, 0, false});
    res->view_bytes = res->geometry_bytes = res->frame_bytes = 0;
    res->view_updates = res->view_refinements = res->view_predicted = res->view_zoomed = 0;
    res->view_mcus = res->view_mcus_coded = 0;
    res->bytes_by_frame.assign(n, 0);
    // A view into a slot: WVUP with its camera's pose, then its image:
    // intra, or a residual against what the client then holds (its
    // prediction of the view, whichever is better; a refinement's base).
    const auto put_view = [&](uint32_t slot, uint32_t camera, size_t update, int quality, bool refine) {
      const size_t before = w.size();
      uint8_t vb[kWalkViewMaxBytes];
      WalkViewUpdate u;
      u.slot = static_cast<uint8_t>(slot);
      u.zoom = zoom_of(camera);
      u.predict = o.predict && !refine;
      u.pose = poses[frame_of(camera)];
      w.add_chunk(chunk::kWalkView, std::span<const uint8_t>(vb, walk_view_to_bytes(u, vb)));
      client.feed(w);
      const EncodedImage* image = refine ? &intra(camera, quality) : &update_image(update, quality);
      EncodedImage residual;
      if (refine || client.predicted()) {
        const Planes base = client.slot(static_cast<uint8_t>(slot));
        ImageEncodeOptions ro = refine ? view_options(std::min(100, quality + o.refine_delta), {})
                                       : view_options(quality, update_region[update]);
        ro.mode = ImageMode::residual;
        ro.prediction = &base;
        residual = encode_planes(view_planes.at(camera), ro);
        // Rate and distortion together: about 3.5 dB a doubling of bytes
        // is where these images' curves run.
        const auto merit = [](const EncodedImage& e) { return e.psnr - 3.5 * std::log2(static_cast<double>(e.coded_bytes())); };
        if (refine || merit(residual) > merit(*image)) {
          image = &residual;
          if (!refine) ++res->view_predicted;
        }
      }
      add_image_chunks(w, *image);
      client.feed(w);
      res->view_bytes += w.size() - before;
      return w.size() - before;
    };
    for (size_t r = 0; r < record_start.size(); ++r) {
      const uint32_t f = static_cast<uint32_t>(record_start[r]);
      const uint32_t last = static_cast<uint32_t>(record_end(r) - 1);
      for (size_t k = 0; k < vp.updates[f].size(); ++k) {
        const size_t u = update_of[f][k];
        written.push_back({put_view(vp.updates[f][k].slot, update_camera[u], u, q[u], false), f, f, false});
        ++res->view_updates;
        res->view_zoomed += vp.updates[f][k].zoom != kWalkZoomUnit ? 1 : 0;
        res->view_mcus += vp.updates[f][k].mcus.size();
        res->view_mcus_coded += update_region[u].empty() ? vp.updates[f][k].mcus.size()
                                                         : static_cast<size_t>(std::count(update_region[u].begin(), update_region[u].end(), uint8_t{1}));
      }
      for (const Refine& rf : refines[f]) {
        written.push_back({put_view(rf.slot, rf.camera, rf.update, q[rf.update], true), f, f, false});
        ++res->view_refinements;
      }
      const size_t before = w.size();
      w.add_chunk(chunk::kWalkFrame, wfrm[r]);
      client.feed(w);
      written.push_back({w.size() - before, f, last, true});
      // Each frame's part; the record's framing and the views before it go with its first.
      for (const WalkPiece& piece : written)
        if (piece.first_frame == f && !piece.record) res->bytes_by_frame[f] += piece.bytes;
      size_t shares = 0;
      for (uint32_t g = f; g <= last; ++g) shares += frame_share[g], res->bytes_by_frame[g] += frame_share[g];
      res->bytes_by_frame[f] += (w.size() - before) - std::min(shares, w.size() - before);
      // The record's geometry and the rest (its poses, views and the chunk's framing).
      res->geometry_bytes += std::min(geometry_part[r], wfrm[r].size());
      res->frame_bytes += w.size() - before - std::min(geometry_part[r], wfrm[r].size());
    }
    res->stream = w.finish();
    // The stream's end goes with the last frame.
    res->bytes_by_frame.back() += res->stream.size() - std::accumulate(res->bytes_by_frame.begin(), res->bytes_by_frame.end(), size_t{0});
    res->slots = slots;
    res->polygons_sent = geo.first_sends + geo.resends;
    res->polygons_resent = geo.resends;
    res->workspace_bytes = h.workspace_bytes;
    res->kbps = res->stream.size() * 8.0 / (n / path.fps) / 1000;
    res->preroll_ms = preroll_ms;
  };
  const size_t updates = update_camera.size();
  const auto preroll_of = [&](const std::vector<WalkPiece>& p) { return walk_preroll_ms(p, lk, kWalkMaxPrerollMs); };
  std::vector<int> q(updates, std::max(0, o.quality));
  // No schedule fits when even the lowest quality (or the one asked for)
  // cannot bring every frame in time at the rate with any pre-roll: what
  // follows a held record must fit the client's window (geometry bursts
  // on entering large rooms). The stream is then untimed (the client shows
  // each frame when its data is whole) and the rate control keeps only the
  // average within the rate.
  const bool timed = preroll_of(pieces_at(q)) != UINT32_MAX;
  if (!timed) wp.rate_bytes = wp.buffer_bytes = 0;
  const auto total = [](const std::vector<WalkPiece>& p) {
    size_t b = 0;
    for (const WalkPiece& x : p) b += x.bytes;
    return b;
  };
  // A target even the lowest quality cannot meet becomes the least
  // pre-roll there is plus the target: at the least there is, the views
  // where updates crowd could not rise above the lowest quality.
  uint32_t target = o.preroll_ms;
  if (timed && o.quality < 0 && updates > 0) {
    const uint32_t least = preroll_of(pieces_at(q));
    if (least > target) target = std::min(kWalkMaxPrerollMs, least + target);
  }
  // Whether views at qualities `qq` keep the stream in time with the target
  // pre-roll (untimed: within the rate on average).
  const auto fits = [&](const std::vector<int>& qq) {
    const std::vector<WalkPiece> p = pieces_at(qq);
    return timed ? preroll_of(p) <= target : total(p) <= lk.rate_bytes * n / path.fps;
  };
  if (o.quality < 0 && updates > 0) {
    // The best quality for every view that fits (bisection: bytes rise with quality) ...
    int lo = -1, hi = 101;
    while (hi - lo > 1) {
      const int mid = (lo + hi) / 2;
      (fits(std::vector<int>(updates, mid)) ? lo : hi) = mid;
      progress("rate control", static_cast<size_t>(7 - std::log2(hi - lo)), 7);
    }
    std::fill(q.begin(), q.end(), std::max(lo, 0));
    // ... then, a step at a time, the view whose next step buys the most
    // (its lower error over the pixels it serves, per byte) while the
    // stream still fits: views serving many pixels for long rise, and
    // where the link has room (long holds) the views there rise, those
    // where updates crowd staying where they are.
    std::vector<double> served(updates, 0);  // pixel-frames each update's view serves
    {
      std::vector<int64_t> current(static_cast<size_t>(o.views), -1);
      for (size_t f = 0; f < n; ++f) {
        for (size_t k = 0; k < vp.updates[f].size(); ++k) current[vp.updates[f][k].slot] = static_cast<int64_t>(update_of[f][k]);
        for (size_t i = 0; i < visible[f].size(); ++i) {
          const int8_t c = vp.choice[f][i];
          if (c >= 0 && current[static_cast<size_t>(c)] >= 0) served[static_cast<size_t>(current[static_cast<size_t>(c)])] += visible[f][i].second;
        }
      }
    }
    constexpr int kStep = 2;
    const auto mse = [&](size_t u, int qq) { return std::pow(10.0, -intra(update_camera[u], qq).psnr / 10); };
    std::priority_queue<std::pair<double, size_t>> next;  // (error removed per byte, update)
    const auto offer = [&](size_t u) {
      if (q[u] + kStep > 100) return;
      const double gain = served[u] * (mse(u, q[u]) - mse(u, q[u] + kStep));
      const double cost = static_cast<double>(intra(update_camera[u], q[u] + kStep).coded_bytes()) -
                          static_cast<double>(intra(update_camera[u], q[u]).coded_bytes());
      next.push({cost > 0 ? gain / cost : std::numeric_limits<double>::max(), u});
    };
    for (size_t u = 0; u < updates; ++u) offer(u);
    for (size_t tried = 0; !next.empty(); ++tried) {
      const size_t u = next.top().second;
      next.pop();
      q[u] += kStep;
      if (fits(q)) offer(u);
      else q[u] -= kStep;  // what rises later only takes more room: this view stays
      if (tried % 16 == 0)
        progress("rate control: the views' mean quality", static_cast<size_t>(std::accumulate(q.begin(), q.end(), 0) / updates), 100);
    }
  }
  // The stream, stating the pre-roll it needs as written (the model's
  // figure unless residuals changed the sizes).
  WalkEncodeResult r;
  uint32_t stated = timed ? preroll_of(pieces_at(q)) : 0;
  for (int attempt = 0;; ++attempt) {
    build(q, stated, &r);
    const uint32_t need = timed ? preroll_of(written) : 0;
    if (need == stated) break;
    if (attempt >= 8) throw std::logic_error("encode_walk: the pre-roll does not settle");
    if (need == UINT32_MAX && o.quality >= 0)
      throw std::runtime_error("encode_walk: with its residual views the stream no longer fits the rate with any pre-roll");
    // Over the target: every view a step lower (rate control only).
    if (need > target && o.quality < 0)
      for (int& v : q) v = std::max(0, v - 2);
    stated = need > target && o.quality < 0 ? preroll_of(pieces_at(q)) : need;
  }
  r.view_quality = q;
  r.quality = updates > 0 ? static_cast<int>(std::lround(std::accumulate(q.begin(), q.end(), 0.0) / updates)) : 0;
  r.rate_bytes = wp.rate_bytes;
  r.buffer_bytes = wp.buffer_bytes;
  r.pieces = written;
  for (const WalkPiece& p : written) {
    r.first_frame_bytes += p.bytes;
    if (p.record) break;
  }
  // 6. What the client shows, against the ground truth.
  std::vector<io::Image> shown;
  r.frame_crc = client_frame_crcs(r.stream, &shown);
  if (shown.size() != n) throw std::logic_error("encode_walk: the client showed " + std::to_string(shown.size()) + " frames of " + std::to_string(n));
  double se = 0;
  for (size_t f = 0; f < n; ++f) {
    const double m = io::mse(truth[f], shown[f]);
    se += m;
    r.frame_psnr.push_back(m > 0 ? 10 * std::log10(255.0 * 255.0 / m) : 99);
  }
  const double mse = se / n;
  r.psnr_rgb = mse > 0 ? 10 * std::log10(255.0 * 255.0 / mse) : 99;
  if (keep_frames) r.frames = std::move(shown);
  return r;
}

}  // namespace vds::enc
