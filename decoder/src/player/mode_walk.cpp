// Player mode "walkthrough": view-dependent texture streaming along a
// camera script (vds/walk.h, vds/walk_geometry.h; docs/walkthrough.md).
// Set up at WLKP for the slots and views it declares; a WFRM record brings
// one or more frames' triangles, hot slots and cameras, and each frame is
// drawn as it is read by mapping each hot triangle from the stored view
// the record names for it (Shading::view_mapped, the screen -> view
// homography of its plane).
// Views arrive as WVUP (the view's pose, and a zoom: its focal length
// times zoom / 16) and an intra vds image decoded into the view's
// Y'CbCr 4:2:0 planes; a WVUP naming a slot's own camera again may carry a
// residual image that refines what the slot holds, and one with its
// "predict" bit has the client draw the view from what it holds first
// (predict_view), which the image may then be a residual against. Any of
// them may be a region image: the MCUs it does not code keep what the slot
// held (the encoder leaves out only MCUs no frame reads while the view
// serves).
#include "vds/homography.h"
#include "vds/player.h"
#include "vds/render.h"

namespace vds {

struct WalkPlay {
  WalkParams params;
  Renderer renderer;
  Camera view_cam[kWalkMaxViews];
  bool view_ready[kWalkMaxViews];
  Texture view_tex[kWalkMaxViews];
  Texture bordered[kWalkMaxViews];  // the same with their borders (predictions)
  int pending = -1;  // the view slot a WVUP opened, until its image is whole
  Camera pending_cam;
  bool pending_refines = false;  // the WVUP names the slot's own camera: its image may be a residual
  bool pending_predicted = false;  // the slot holds the view's prediction: its image may be a residual
  bool image_open = false;
  Mesh* meshes = nullptr;
  Vec3<Q16_16>* positions = nullptr;
  uint16_t* indices = nullptr;
  uint8_t* view_of = nullptr;
  uint16_t* hot_stamp = nullptr;     // per slot: walk_frame_stamp of the frame it was last hot in
  bool fresh[kWalkMaxViews] = {};    // a view update since the last frame
};

namespace {

// A view's planes carry a border of mid grey around the image (2 luma
// texels, 1 chroma texel) that no image writes: a prediction drawing from
// a view (predict_view) reads grey wherever a triangle reaches past it.
constexpr uint32_t kBorder = 2;
size_t plane_bytes(const WalkParams& w) {
  const size_t cw = (w.view_width + 1u) / 2u + kBorder, ch = (w.view_height + 1u) / 2u + kBorder;
  return (static_cast<size_t>(w.view_width) + 2 * kBorder) * (w.view_height + 2 * kBorder) + 2 * cw * ch;
}

// The view with its border, for predictions: its camera's principal point
// moves by the border.
Texture with_border(const Texture& t) {
  Texture b = t;
  b.width = static_cast<uint16_t>(t.width + 2 * kBorder);
  b.height = static_cast<uint16_t>(t.height + 2 * kBorder);
  b.texels = static_cast<const uint8_t*>(t.texels) - kBorder * t.stride - kBorder;
  b.cb = t.cb - (kBorder / 2) * t.chroma_stride - kBorder / 2;
  b.cr = t.cr - (kBorder / 2) * t.chroma_stride - kBorder / 2;
  return b;
}

// A triangle crossing several bands is set up once while it stays in the
// set-up cache instead of once a band: 32 entries (about 14 KB on the
// Cortex-M4) take about 6 % off a frame of oa_dm4 and oa_dm5
// (docs/walkthrough.md); the frames are the same with any cache.
constexpr uint32_t kWalkSetupCache = 32;

RenderConfig render_config(const StreamHeader& h, const WalkParams& w, const PlayerConfig& c) {
  RenderConfig rc = detail::band_render_config(h, c, 3u * w.slots, w.slots);
  rc.setup_cache = kWalkSetupCache;
  return rc;
}

bool cameras_equal(const Camera& a, const Camera& b) {
  for (int r = 0; r < 3; ++r)
    for (int c = 0; c < 3; ++c)
      if (a.rotation.m[r][c].raw() != b.rotation.m[r][c].raw()) return false;
  return a.position.x.raw() == b.position.x.raw() && a.position.y.raw() == b.position.y.raw() &&
         a.position.z.raw() == b.position.z.raw() && a.fx.raw() == b.fx.raw() && a.fy.raw() == b.fy.raw();
}

bool start(Player& p, const StreamHeader& h) {
  p.walk = nullptr;
  return detail::header_has_camera_and_frames(p, h, "a walkthrough needs a camera and a frame count in its header");  // set up at WLKP
}

bool setup(Player& p, const uint8_t* payload, uint32_t size) {
  WalkParams w;
  if (walk_params_from_bytes(payload, size, &w) != Status::ok || w.slots > kWalkMaxSlots ||
      w.view_width > p.header().width || w.view_height > p.header().height) {
    p.fail(Status::malformed, "WLKP is not valid (or its views are larger than the frame)");
    return false;
  }
  const StreamHeader& h = p.header();
  const size_t need = Player::walk_workspace_bytes(h, w, p.config());
  PlayerPlan plan = p.plan();
  plan.known = true;
  plan.needs = need;
  plan.available = p.arena().remaining();
  plan.triangles = w.slots;
  p.set_plan(plan);
  if (need > p.arena().remaining()) {
    p.fail(Status::workspace_too_small, "the walkthrough's slots and views do not fit the workspace");
    return false;
  }
  WalkPlay* wp = static_cast<WalkPlay*>(p.arena().alloc(sizeof(WalkPlay), alignof(WalkPlay)));
  if (wp == nullptr) return false;
  *wp = WalkPlay{};
  wp->params = w;
  if (w.rate_bytes != 0 && h.frame_period_us != 0) p.set_schedule(w.preroll_ms);
  Status s = p.walk_geometry.init(p.arena(), w.slots, w.quantum_raw);
  if (s == Status::ok) s = p.image.init(p.arena());
  if (s == Status::ok) s = wp->renderer.init(render_config(h, w, p.config()), p.arena());
  wp->meshes = p.arena().alloc_array<Mesh>(w.slots);
  wp->positions = p.arena().alloc_array<Vec3<Q16_16>>(3u * w.slots);
  wp->indices = p.arena().alloc_array<uint16_t>(3u * w.slots);
  wp->view_of = p.arena().alloc_array<uint8_t>(w.slots);
  wp->hot_stamp = p.arena().alloc_array<uint16_t>(w.slots);
  if (s == Status::ok && (!wp->meshes || !wp->positions || !wp->indices || !wp->view_of || !wp->hot_stamp))
    s = Status::workspace_too_small;
  for (uint8_t v = 0; v < w.views && s == Status::ok; ++v) {
    uint8_t* planes = static_cast<uint8_t*>(p.arena().alloc(plane_bytes(w), 4));
    if (planes == nullptr) {
      s = Status::workspace_too_small;
      break;
    }
    for (size_t i = 0; i < plane_bytes(w); ++i) planes[i] = 128;
    // The image inside the border.
    Texture& t = wp->view_tex[v];
    t.format = TexFormat::ycbcr420;
    t.address = TexAddress::clamp;
    t.width = w.view_width;
    t.height = w.view_height;
    t.stride = w.view_width + 2 * kBorder;
    t.chroma_stride = (w.view_width + 1u) / 2u + kBorder;
    const size_t chroma_plane = t.chroma_stride * ((w.view_height + 1u) / 2u + kBorder);
    uint8_t* const cb = planes + static_cast<size_t>(t.stride) * (w.view_height + 2 * kBorder);
    t.texels = planes + kBorder * t.stride + kBorder;
    t.cb = cb + (kBorder / 2) * t.chroma_stride + kBorder / 2;
    t.cr = cb + chroma_plane + (kBorder / 2) * t.chroma_stride + kBorder / 2;
    wp->view_ready[v] = false;
    wp->bordered[v] = with_border(t);
  }
  if (s != Status::ok) {
    p.fail(s, "the walkthrough could not be set up");
    return false;
  }
  for (uint32_t i = 0; i < 3u * w.slots; ++i) wp->indices[i] = static_cast<uint16_t>(i);
  for (uint32_t i = 0; i < w.slots; ++i) wp->view_of[i] = 0, wp->hot_stamp[i] = 0;
  p.walk_frames.reset();
  p.walk = wp;
  return true;
}

// Triangle i of a draw list: its positions, and a mesh mapping it from a view.
Mesh& put_triangle(WalkPlay& w, uint32_t i, const Vec3<Q16_16>* tri) {
  for (int k = 0; k < 3; ++k) w.positions[3 * i + static_cast<uint32_t>(k)] = tri[k];
  Mesh& m = w.meshes[i];
  m = Mesh{};
  m.indices = &w.indices[3 * i];
  m.shading = Shading::view_mapped;
  m.filter = Filter::bilinear_luma;  // chroma nearest: a fifth fewer instructions a pixel, 0.03 dB (docs/walkthrough.md)
  m.cull = Cull::none;
  return m;
}

DrawList draw_list(const WalkPlay& w, uint32_t n) {
  DrawList list;
  list.positions = w.positions;
  list.num_positions = 3 * n;
  list.meshes = w.meshes;
  list.num_meshes = n;
  return list;
}

Status draw(Player& p, WalkPlay& w, const WalkPose& pose) {
  Camera cam;
  if (walk_camera(p.header(), pose, &cam) != Status::ok) return Status::malformed;
  const uint16_t* hot = p.walk_geometry.hot();
  const uint32_t n = p.walk_geometry.hot_count();
  for (uint32_t i = 0; i < n; ++i) {
    Mesh& m = put_triangle(w, i, p.walk_geometry.triangle(hot[i]));
    m.texture = &w.view_tex[w.view_of[hot[i]]];
    m.num_triangles = 0;
  }
  // Each view's triangles, with what the screen's and the view's cameras
  // alone give computed once (the same homographies; a triangle then
  // costs a rank-one update of a matrix, vds/homography.h).
  for (uint8_t v = 0; v < kWalkMaxViews; ++v) {
    if (!w.view_ready[v]) continue;
    HomographyCameras pair;
    Status ps = Status::invalid_argument;
    bool pair_made = false;
    for (uint32_t i = 0; i < n; ++i) {
      if (w.view_of[hot[i]] != v) continue;
      if (!pair_made) {
        ps = homography_cameras(cam, w.view_cam[v], &pair);
        pair_made = true;
      }
      Mesh& m = w.meshes[i];
      m.num_triangles = ps == Status::ok && plane_homography(pair, p.walk_geometry.triangle(hot[i]), &m.view_map) == Status::ok ? 1 : 0;
    }
  }
  return w.renderer.render(cam, draw_list(w, n), 0, detail::render_band_to_player, &p);
}

// A view's prediction: the band's RGB565 rows into the slot's Y'CbCr
// 4:2:0 planes (JFIF equations in 16-bit fixed point, chroma from the sum
// of each 2x2 block; bands start on even rows).
struct PredictTarget {
  const Texture* t;
};

inline void rgb_of(uint16_t c, int32_t& r, int32_t& g, int32_t& b) {
  const int32_t r5 = c >> 11, g6 = (c >> 5) & 63, b5 = c & 31;
  r = (r5 << 3) | (r5 >> 2);
  g = (g6 << 2) | (g6 >> 4);
  b = (b5 << 3) | (b5 >> 2);
}

bool predict_band(void* ctx, const Band& b) {
  const Texture& t = *static_cast<const PredictTarget*>(ctx)->t;
  if (b.format != PixelFormat::rgb565 || (b.y & 1) != 0) return false;
  // The frame is drawn whole; the view is its top left (at most as large).
  const uint16_t rows = b.y >= t.height ? 0 : (b.y + b.height > t.height ? static_cast<uint16_t>(t.height - b.y) : b.height);
  const uint16_t cols = b.width < t.width ? b.width : t.width;
  uint8_t* yp = static_cast<uint8_t*>(const_cast<void*>(t.texels));
  for (uint16_t row = 0; row < rows; row += 2) {
    const uint16_t* p0 = reinterpret_cast<const uint16_t*>(b.pixels + static_cast<size_t>(row) * b.stride);
    const bool pair = row + 1 < rows;
    const uint16_t* p1 = pair ? reinterpret_cast<const uint16_t*>(b.pixels + static_cast<size_t>(row + 1) * b.stride) : p0;
    uint8_t* y0 = yp + static_cast<size_t>(b.y + row) * t.stride;
    uint8_t* y1 = y0 + t.stride;
    const size_t crow = static_cast<size_t>((b.y + row) >> 1) * t.chroma_stride;
    uint8_t* cb = const_cast<uint8_t*>(t.cb) + crow;
    uint8_t* cr = const_cast<uint8_t*>(t.cr) + crow;
    for (uint16_t x = 0; x < cols; x += 2) {
      int32_t rs = 0, gs = 0, bs = 0, n = 0;
      for (int dy = 0; dy < 2; ++dy)
        for (int dx = 0; dx < 2; ++dx) {
          if (x + dx >= cols || (dy == 1 && !pair)) continue;
          int32_t r, g, bl;
          rgb_of((dy ? p1 : p0)[x + dx], r, g, bl);
          (dy ? y1 : y0)[x + dx] = static_cast<uint8_t>((19595 * r + 38470 * g + 7471 * bl + 32768) >> 16);
          rs += r, gs += g, bs += bl, ++n;
        }
      // Means of the block (n is 1, 2 or 4), rounded; never below 0.
      const int sh = 16 + (n >> 1);
      const int32_t half = int32_t{1} << (sh - 1);
      cb[x >> 1] = static_cast<uint8_t>((128 * 65536 * n - 11059 * rs - 21709 * gs + 32768 * bs + half) >> sh);
      cr[x >> 1] = static_cast<uint8_t>((128 * 65536 * n + 32768 * rs - 27439 * gs - 5329 * bs + half) >> sh);
    }
  }
  return true;
}

// Whether a triangle lies in front of a view's near plane.
bool in_front(const Camera& v, const Vec3<Q16_16>* tri) {
  for (int k = 0; k < 3; ++k)
    if (camera_transform(v, tri[k]).z.raw() <= v.near_z.raw()) return false;
  return true;
}

// Before a view update's image: every triangle the client holds drawn at
// the new view's camera from a view it lies in front of — its own view
// first, then the others in order, never the slot being replaced — into
// the slot's planes; what no view shows is mid grey (the views' borders
// and the background). *predicted is false when the client holds no other
// view: nothing is drawn.
Status predict_view(Player& p, WalkPlay& w, int slot, bool* predicted) {
  *predicted = false;
  int other = -1;
  for (int v = 0; v < w.params.views && other < 0; ++v)
    if (v != slot && w.view_ready[v]) other = v;
  if (other < 0) return Status::ok;
  uint32_t n = 0;
  for (uint32_t slot_i = 0; slot_i < w.params.slots; ++slot_i) {
    const Vec3<Q16_16>* tri = p.walk_geometry.triangle(slot_i);
    if (tri == nullptr) continue;
    Mesh& m = put_triangle(w, n++, tri);
    const uint8_t own = w.view_of[slot_i];
    int v = own != slot && own < w.params.views && w.view_ready[own] && in_front(w.view_cam[own], tri) ? own : -1;
    for (int u = 0; u < w.params.views && v < 0; ++u)
      if (u != slot && w.view_ready[u] && in_front(w.view_cam[u], tri)) v = u;
    m.texture = &w.bordered[v >= 0 ? v : other];
    Camera from = w.view_cam[v >= 0 ? v : other];
    from.cx = Q16_16::from_raw(from.cx.raw() + static_cast<int32_t>(kBorder << 16));
    from.cy = Q16_16::from_raw(from.cy.raw() + static_cast<int32_t>(kBorder << 16));
    m.num_triangles = v >= 0 && plane_homography(w.pending_cam, from, tri, &m.view_map) == Status::ok ? 1 : 0;
  }
  PredictTarget target{&w.view_tex[slot]};
  constexpr uint32_t kGrey = 0x808080;
  const Status s = w.renderer.render(w.pending_cam, draw_list(w, n), kGrey, predict_band, &target);
  *predicted = s == Status::ok;
  return s;
}

ChunkResult on_chunk(Player& p, uint32_t type, const uint8_t* payload, uint32_t size) {
  const bool walk_chunk = type == chunk::kWalkParams || type == chunk::kWalkView || type == chunk::kWalkFrame ||
                          type == chunk::kImageHeader || type == chunk::kImageData;
  if (!walk_chunk) return ChunkResult::unknown;
  if (p.walk == nullptr) {
    if (type != chunk::kWalkParams) {
      p.fail(Status::malformed, "a walkthrough chunk before WLKP");
      return ChunkResult::abort;
    }
    const uint64_t t0 = p.enter_chunk();
    const bool ok = setup(p, payload, size);
    p.add_decode(p.work_clock() - t0);
    p.leave_chunk();
    return ok ? ChunkResult::consumed : ChunkResult::abort;
  }
  WalkPlay& w = *p.walk;
  const uint64_t t0 = p.enter_chunk();
  ChunkResult result = ChunkResult::consumed;
  const auto refuse = [&](Status s, const char* why) {
    p.fail(s, why);
    result = ChunkResult::abort;
  };
  if (type == chunk::kWalkParams) {
    refuse(Status::malformed, "a second WLKP");
  } else if (type == chunk::kWalkView) {
    WalkViewUpdate u;
    if (w.pending >= 0) refuse(Status::malformed, "a view update before the last one's image is whole");
    else if (walk_view_from_bytes(payload, size, &u) != Status::ok || u.slot >= w.params.views)
      refuse(Status::malformed, "WVUP is not valid");
    else if (walk_view_camera(p.header(), w.params, u.pose, &w.pending_cam, u.zoom) != Status::ok)
      refuse(Status::malformed, "WVUP's camera is not valid");
    else {
      w.pending = u.slot;
      w.fresh[u.slot] = true;
      w.image_open = false;
      // The slot's own camera again: a refinement, added to what the slot
      // holds. Another camera: the slot is given the view's prediction
      // when the update asks for it.
      w.pending_refines = w.view_ready[u.slot] && cameras_equal(w.view_cam[u.slot], w.pending_cam);
      w.pending_predicted = false;
      if (!w.pending_refines) {
        w.view_ready[u.slot] = false;
        if (u.predict && predict_view(p, w, u.slot, &w.pending_predicted) != Status::ok)
          refuse(Status::malformed, "a view's prediction could not be drawn");
      }
    }
  } else if (type == chunk::kImageHeader || type == chunk::kImageData) {
    if (w.pending < 0) {
      refuse(Status::malformed, "an image outside a view update");
    } else {
      const Texture& t = w.view_tex[w.pending];
      if (type == chunk::kImageHeader) {
        ImageHeader ih;
        if (w.image_open || image_header_from_bytes(payload, size, &ih) != Status::ok || ih.width != t.width ||
            ih.height != t.height || ih.chroma != ChromaFormat::yuv420 || (ih.residual() && !w.pending_refines && !w.pending_predicted))
          refuse(Status::malformed, "a view's image must be a 4:2:0 image of the views' size, a residual only on a prediction or its own view");
        else
          w.image_open = true;
      }
      if (result == ChunkResult::consumed) {
        uint8_t* y = static_cast<uint8_t*>(const_cast<void*>(t.texels));
        const ImageTarget target =
            ImageTarget::planes(y, t.stride, const_cast<uint8_t*>(t.cb), t.chroma_stride, const_cast<uint8_t*>(t.cr), t.chroma_stride);
        const Status s = w.image_open ? p.image.on_chunk(type, payload, size, target) : Status::malformed;
        if (is_error(s)) {
          refuse(s, "a view's image was refused");
        } else if (s == Status::ok && p.image.done()) {
          image_deblock(p.image.header(), target);
          w.view_cam[w.pending] = w.pending_cam;
          w.view_ready[w.pending] = true;
          w.pending = -1;
          w.image_open = false;
        }
      }
    }
  } else {  // WFRM: frames, each drawn as it is read
    ArithDecoder d;
    uint32_t frames = 0;
    if (w.pending >= 0) {
      refuse(Status::malformed, "a frame while a view's image is incomplete");
    } else if (d.init(payload, size) != Status::ok || (frames = p.walk_frames.read_count(d, w.params.frames_per_record)) == 0) {
      refuse(d.ok() ? Status::malformed : d.status(), "WFRM was refused");
    }
    for (uint32_t k = 0; k < frames && result == ChunkResult::consumed; ++k) {
      const uint64_t f0 = k == 0 ? t0 : p.work_clock();
      WalkPose pose;
      Status s = p.walk_geometry.decode(d);
      if (s == Status::ok)
        s = p.walk_frames.decode(d, p.walk_geometry.hot(), p.walk_geometry.hot_count(), w.view_of, w.hot_stamp, w.fresh,
                                 w.params.views, &pose);
      for (bool& f : w.fresh) f = false;
      if (s == Status::ok && k + 1 == frames) s = d.finish();
      p.add_decode(p.work_clock() - f0);
      if (s != Status::ok) {
        refuse(s, "WFRM was refused");
      } else if (!p.begin_frame()) {
        result = ChunkResult::abort;
      } else {
        const uint64_t display_before = p.display_total();
        const uint64_t d0 = p.work_clock();
        const Status ds = draw(p, w, pose);
        p.add_display((p.work_clock() - d0) - (p.display_total() - display_before));
        if (ds != Status::ok) refuse(ds, "the frame could not be drawn");
        else if (!p.end_frame()) result = ChunkResult::abort;
      }
    }
    p.leave_chunk();
    return result;
  }
  p.add_decode(p.work_clock() - t0);
  p.leave_chunk();
  return result;
}

// Frames complete at WFRM chunks, up to WLKP's frames-per-record each (one
// a chunk until WLKP is read): no more chunks than that many fit the room.
size_t feed_limit(const Player& p, uint32_t frames_room) {
  const uint32_t per_chunk = p.walk != nullptr ? p.walk->params.frames_per_record : 1u;
  return detail::chunk_per_frame_feed_limit(frames_room / per_chunk);
}

}  // namespace

const Texture* Player::walk_view(uint8_t slot) const {
  return walk != nullptr && slot < walk->params.views ? &walk->view_tex[slot] : nullptr;
}

bool Player::walk_view_predicted() const { return walk != nullptr && walk->pending >= 0 && walk->pending_predicted; }

size_t Player::walk_workspace_bytes(const StreamHeader& h, const WalkParams& w, const PlayerConfig& c) {
  const RenderConfig rc = render_config(h, w, c);
  // Each allocation of setup() with its worst alignment slack.
  return sizeof(WalkPlay) + alignof(WalkPlay) + WalkGeometry::workspace_bytes(w.slots) + ImageDecoder::kWorkspaceBytes +
         render_workspace_size(rc) + w.slots * sizeof(Mesh) + alignof(Mesh) + 3u * w.slots * sizeof(Vec3<Q16_16>) +
         alignof(Vec3<Q16_16>) + 3u * w.slots * sizeof(uint16_t) + alignof(uint16_t) + w.slots + w.slots * sizeof(uint16_t) +
         alignof(uint16_t) + w.views * (plane_bytes(w) + 4);
}

namespace detail {
extern const PlayerMode kWalkMode;
const PlayerMode kWalkMode{StreamMode::walkthrough, start, on_chunk, feed_limit};
}  // namespace detail

}  // namespace vds
