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
  const WalkGeometry* geometry = nullptr;
  Camera view_cam[kWalkMaxViews];
  bool view_ready[kWalkMaxViews];
  Texture view_tex[kWalkMaxViews];
  Texture bordered[kWalkMaxViews];  // the same with their borders (predictions)
  int pending = -1;  // the view slot a WVUP opened, until its image is whole
  Camera pending_cam;
  bool pending_refines = false;  // the WVUP names the slot's own camera: its image may be a residual
  bool pending_predicted = false;  // the slot holds the view's prediction: its image may be a residual
  bool image_open = false;
  // The frame's draw list: one mesh of the faces drawn, each from the
  // view and homography frame_map() gives it at its set-up: a hot slot's
  // triangle, or two hot slots' quad (WalkGeometry::joins_next) seen
  // from one view. Slot s's vertices are 3 s + k; 3 indices a triangle,
  // 4 a quad (at most 3 a hot slot). Before that, the frame's sort keys
  // (put_key: 4 bytes a face, 4-byte aligned).
  uint16_t* indices = nullptr;
  uint8_t* corners = nullptr;  // per face of the draw list: 3 or 4
  uint8_t* view_of = nullptr;
  uint16_t* hot_stamp = nullptr;     // per slot: walk_frame_stamp of the frame it was last hot in
  bool fresh[kWalkMaxViews] = {};    // a view update since the last frame
  // What the screen's and each view's cameras alone give (vds/homography.h),
  // computed once a frame when a triangle first asks for that view.
  HomographyCameras pair[kWalkMaxViews];
  uint8_t pair_state[kWalkMaxViews] = {};  // kUnknown, kMade or kFailed this frame
  // The homographies of slots [0, kept) as the frame first asks for them
  // (the spare workspace's: a triangle set up in several bands then costs
  // one); map_state as pair_state.
  Homography* maps = nullptr;
  uint8_t* map_state = nullptr;
  uint32_t kept = 0;
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
// (docs/walkthrough.md); the frames are the same with any cache. A
// workspace with room to spare holds up to kWalkSetupCacheMost: on the
// client firmware's, 48 took oa_dm5 furthest (64 and 128 leave fewer
// projected vertices there; in 4 MiB they save 1 and 2 % more).
constexpr uint32_t kWalkSetupCache = 32;
constexpr uint32_t kWalkSetupCacheMost = 48;
// Faces spanning at most 8 pixel columns and rows are drawn in one colour,
// their view's sample at their first triangle's centre (frame_point): on
// the figure maps' tours at 16 and 32 kbit/s the same PSNR to 0.01 dB as
// every face mapped (12: up to 0.03 dB less; 16: up to 0.10), for about 4 %
// fewer Cortex-M4 instructions on oa_dm5's busiest stretch
// (docs/walkthrough.md).
constexpr uint8_t kWalkPointFaceSpan = 8;

RenderConfig render_config(const StreamHeader& h, const WalkParams& w, const PlayerConfig& c, uint32_t vertex_cache,
                           uint32_t setup_cache = kWalkSetupCache) {
  RenderConfig rc = detail::band_render_config(h, c, vertex_cache, w.slots);
  rc.setup_cache = setup_cache;
  rc.point_face_span = kWalkPointFaceSpan;
  return rc;
}

constexpr uint8_t kUnknown = 0, kMade = 1, kFailed = 2;

// What a workspace larger than the walkthrough needs buys, in this order
// (each makes the frames cheaper, never different): set-up cache entries
// up to kWalkSetupCacheMost, the renderer's cache of projected vertices,
// then the homographies kept a frame (docs/walkthrough.md, "The client on
// the Cortex-M4 board").
struct WalkSpare {
  uint32_t setups = kWalkSetupCache;  // the renderer's set-up cache
  uint32_t vertices = 0;  // the renderer's vertex cache
  uint32_t maps = 0;      // slots whose homographies are kept
};
constexpr size_t kVertexBytes = sizeof(detail::CachedVertex) + 1;
constexpr size_t kMapBytes = sizeof(Homography) + 1;
constexpr size_t kSpareSlack = 32;  // the alignment of the arrays these add

WalkSpare spare_caches(const StreamHeader& h, const WalkParams& w, const PlayerConfig& c, size_t spare) {
  WalkSpare out;
  spare = spare > kSpareSlack ? spare - kSpareSlack : 0;
  const size_t base = render_workspace_size(render_config(h, w, c, 0));
  for (uint32_t k = kWalkSetupCacheMost; k > kWalkSetupCache; --k) {
    const size_t more = render_workspace_size(render_config(h, w, c, 0, k)) - base;
    if (more <= spare) {
      out.setups = k;
      spare -= more;
      break;
    }
  }
  const size_t verts = spare / kVertexBytes;
  out.vertices = static_cast<uint32_t>(verts < 3u * w.slots ? verts : 3u * w.slots);
  spare -= out.vertices * kVertexBytes;
  const size_t maps = spare / kMapBytes;
  out.maps = static_cast<uint32_t>(maps < w.slots ? maps : w.slots);
  return out;
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
  const WalkSpare spare = spare_caches(h, w, p.config(), p.arena().remaining() - need);
  WalkPlay* wp = static_cast<WalkPlay*>(p.arena().alloc(sizeof(WalkPlay), alignof(WalkPlay)));
  if (wp == nullptr) return false;
  *wp = WalkPlay{};
  wp->params = w;
  wp->geometry = &p.walk_geometry;
  if (w.rate_bytes != 0 && h.frame_period_us != 0) p.set_schedule(w.preroll_ms);
  Status s = p.walk_geometry.init(p.arena(), w.slots, w.quantum_raw);
  if (s == Status::ok) s = p.image.init(p.arena());
  if (s == Status::ok) s = wp->renderer.init(render_config(h, w, p.config(), spare.vertices, spare.setups), p.arena());
  wp->indices = static_cast<uint16_t*>(p.arena().alloc(3u * w.slots * sizeof(uint16_t), 4));
  wp->corners = p.arena().alloc_array<uint8_t>(w.slots);
  wp->view_of = p.arena().alloc_array<uint8_t>(w.slots);
  wp->hot_stamp = p.arena().alloc_array<uint16_t>(w.slots);
  if (s == Status::ok && (!wp->indices || !wp->corners || !wp->view_of || !wp->hot_stamp)) s = Status::workspace_too_small;
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
  if (s == Status::ok && spare.maps != 0) {
    wp->maps = p.arena().alloc_array<Homography>(spare.maps);
    wp->map_state = p.arena().alloc_array<uint8_t>(spare.maps);
    wp->kept = wp->maps != nullptr && wp->map_state != nullptr ? spare.maps : 0;  // else none kept: the same frames
  }
  if (s != Status::ok) {
    p.fail(s, "the walkthrough could not be set up");
    return false;
  }
  for (uint32_t i = 0; i < w.slots; ++i) wp->view_of[i] = 0, wp->hot_stamp[i] = 0;
  p.walk_frames.reset();
  p.walk = wp;
  return true;
}

// The draw list of `n` faces whose indices are in w.indices (their
// corners in `corners`, nullptr: triangles), drawn from the slots' own
// positions, each from the view `map` gives it.
Mesh one_mesh(const WalkPlay& w, uint32_t n, const uint8_t* corners, const Texture* form, const ViewMapSource* map) {
  Mesh m;
  m.indices = w.indices;
  m.num_triangles = n;
  m.corners = corners;
  m.shading = Shading::view_mapped;
  m.filter = Filter::bilinear_luma;  // chroma nearest: a fifth fewer instructions a pixel, 0.03 dB (docs/walkthrough.md)
  m.cull = Cull::none;
  m.texture = form;  // every view's planes have the same form
  m.views = map;
  return m;
}

DrawList draw_list(const WalkPlay& w, const Mesh* mesh) {
  DrawList list;
  list.positions = w.geometry->positions();
  list.num_positions = 3 * w.params.slots;
  list.meshes = mesh;
  list.num_meshes = 1;
  return list;
}

// The slot's triangle at w.indices[at].
void put_triangle(WalkPlay& w, uint32_t at, uint32_t slot) {
  for (uint32_t k = 0; k < 3; ++k) w.indices[at + k] = static_cast<uint16_t>(3 * slot + k);
}
// The quad of slot and slot + 1 (outline code q of joins_next: the next
// slot's corner j between the slot's corners i and i + 1) at w.indices[at].
void put_quad(WalkPlay& w, uint32_t at, uint32_t slot, uint8_t q) {
  const uint32_t i = (q - 1u) / 3u, j = (q - 1u) % 3u;
  w.indices[at] = static_cast<uint16_t>(3 * slot + i);
  w.indices[at + 1] = static_cast<uint16_t>(3 * (slot + 1) + j);
  w.indices[at + 2] = static_cast<uint16_t>(3 * slot + (i + 1) % 3);
  w.indices[at + 3] = static_cast<uint16_t>(3 * slot + (i + 2) % 3);
}

// Sort key i of a frame, in the front of w.indices (whose 6 bytes a hot
// slot hold a face's 4 bytes of key).
uint32_t key_at(const WalkPlay& w, uint32_t i) {
  uint32_t k;
  __builtin_memcpy(&k, reinterpret_cast<const uint8_t*>(w.indices) + 4 * size_t{i}, 4);
  return k;
}
void put_key(WalkPlay& w, uint32_t i, uint32_t k) { __builtin_memcpy(reinterpret_cast<uint8_t*>(w.indices) + 4 * size_t{i}, &k, 4); }

// A face's key: its (first) triangle's centroid's squared distance from
// `c` as a number with 6 bits of exponent and 11 of mantissa (ordered as
// the distance), whether it is a quad (1 bit), then its slot (14 bits:
// kWalkMaxSlots).
static_assert(kWalkMaxSlots <= (1u << 14), "a slot fits a key's low 14 bits");
constexpr uint32_t kKeyQuad = 1u << 14;
uint32_t distance_key(const Vec3<Q16_16>* t, const Vec3<Q16_16>& c, uint32_t slot, bool quad) {
  // Quarter units: a map of +-2^13 units keeps every sum below 2^40.
  const auto d = [](Q16_16 a, Q16_16 b, Q16_16 e, Q16_16 o) {
    return ((int64_t{a.raw()} + b.raw() + e.raw()) >> 14) - 3 * int64_t{o.raw() >> 14};
  };
  const int64_t dx = d(t[0].x, t[1].x, t[2].x, c.x), dy = d(t[0].y, t[1].y, t[2].y, c.y), dz = d(t[0].z, t[1].z, t[2].z, c.z);
  uint64_t d2 = static_cast<uint64_t>(dx * dx) + static_cast<uint64_t>(dy * dy) + static_cast<uint64_t>(dz * dz);
  uint32_t e = 0;
  if (d2 >= (uint64_t{1} << 18)) {
    e = static_cast<uint32_t>(64 - clz64(d2) - 18);
    d2 >>= e;
  }
  return (e << 26) | (static_cast<uint32_t>(d2 >> 7) << 15) | (quad ? kKeyQuad : 0) | slot;
}

// The frame's faces into w.indices and w.corners, nearest first: the
// depth test then turns away most of what lies behind, which costs a
// fraction of a drawn pixel (docs/walkthrough.md). A hot slot whose
// triangle makes a quad with the next slot's (joins_next), that slot hot
// too and both from one view, is drawn with it as one face: one set-up
// and one homography instead of two. A heap sort of the faces' keys in
// place. Returns the number of faces.
uint32_t put_nearest_first(WalkPlay& w, const WalkGeometry& g, const Vec3<Q16_16>& camera) {
  const uint16_t* hot = g.hot();
  const uint32_t hn = g.hot_count();
  uint32_t n = 0;
  for (uint32_t i = 0; i < hn; ++i) {
    const uint32_t s = hot[i];
    const bool quad = i + 1 < hn && hot[i + 1] == s + 1 && g.joins_next(s) != 0 && w.view_of[s] == w.view_of[s + 1];
    put_key(w, n++, distance_key(g.triangle(s), camera, s, quad));
    if (quad) ++i;
  }
  const auto sift = [&w](uint32_t root, uint32_t end) {
    const uint32_t v = key_at(w, root);
    while (2 * root + 1 < end) {
      uint32_t c = 2 * root + 1;
      if (c + 1 < end && key_at(w, c + 1) > key_at(w, c)) ++c;
      const uint32_t kc = key_at(w, c);
      if (kc <= v) break;
      put_key(w, root, kc);
      root = c;
    }
    put_key(w, root, v);
  };
  for (uint32_t i = n / 2; i-- > 0;) sift(i, n);
  for (uint32_t end = n; end > 1; --end) {
    const uint32_t top = key_at(w, 0);
    put_key(w, 0, key_at(w, end - 1));
    put_key(w, end - 1, top);
    sift(0, end - 1);
  }
  // Keys to indices from the last: face i's indices (from byte 6i: the
  // faces before it have at least 3 each) never reach a key not yet read
  // (bytes below 4i).
  uint32_t at = 0;
  for (uint32_t i = 0; i < n; ++i) at += (key_at(w, i) & kKeyQuad) ? 4 : 3;
  for (uint32_t i = n; i-- > 0;) {
    const uint32_t key = key_at(w, i), slot = key & 0x3FFFu;
    if (key & kKeyQuad) {
      at -= 4;
      put_quad(w, at, slot, g.joins_next(slot));
      w.corners[i] = 4;
    } else {
      at -= 3;
      put_triangle(w, at, slot);
      w.corners[i] = 3;
    }
  }
  return n;
}

struct FrameCtx {
  WalkPlay* w;
  const Camera* cam;
};

// A face of the frame: from the view the stream chose for its (first)
// slot, at the homography of that slot's plane between the screen and
// that view (a quad's two triangles share it).
bool frame_map(void* ctx, uint32_t, uint32_t first, const Texture** tex, Homography* out) {
  const FrameCtx& f = *static_cast<const FrameCtx*>(ctx);
  WalkPlay& w = *f.w;
  const uint32_t slot = first / 3u;
  const uint8_t v = w.view_of[slot];
  if (v >= kWalkMaxViews || !w.view_ready[v]) return false;
  if (w.pair_state[v] == kUnknown)
    w.pair_state[v] = homography_cameras(*f.cam, w.view_cam[v], &w.pair[v]) == Status::ok ? kMade : kFailed;
  if (w.pair_state[v] == kFailed) return false;
  *tex = &w.view_tex[v];
  if (slot < w.kept) {
    if (w.map_state[slot] == kUnknown)
      w.map_state[slot] = plane_homography(w.pair[v], w.geometry->triangle(slot), &w.maps[slot]) == Status::ok ? kMade : kFailed;
    *out = w.maps[slot];
    return w.map_state[slot] == kMade;
  }
  return plane_homography(w.pair[v], w.geometry->triangle(slot), out) == Status::ok;
}

// A small face of the frame: the view's pixel position of its (first)
// triangle's centre, in the view the stream chose for its slot.
bool frame_point(void* ctx, uint32_t, uint32_t first, const Texture** tex, int32_t* u_q8, int32_t* v_q8) {
  const FrameCtx& f = *static_cast<const FrameCtx*>(ctx);
  WalkPlay& w = *f.w;
  const uint32_t slot = first / 3u;
  const uint8_t v = w.view_of[slot];
  if (v >= kWalkMaxViews || !w.view_ready[v]) return false;
  const Vec3<Q16_16>* t = w.geometry->triangle(slot);
  const auto mean = [](int32_t a, int32_t b, int32_t c) {
    return Q16_16::from_raw(static_cast<int32_t>((int64_t{a} + b + c) / 3));
  };
  const Vec3<Q16_16> centre{mean(t[0].x.raw(), t[1].x.raw(), t[2].x.raw()), mean(t[0].y.raw(), t[1].y.raw(), t[2].y.raw()),
                            mean(t[0].z.raw(), t[1].z.raw(), t[2].z.raw())};
  const Camera& vc = w.view_cam[v];
  if (!camera_project(vc, camera_transform(vc, centre), u_q8, v_q8)) return false;
  *tex = &w.view_tex[v];
  return true;
}

Status draw(Player& p, WalkPlay& w, const WalkPose& pose) {
  Camera cam;
  if (walk_camera(p.header(), pose, &cam) != Status::ok) return Status::malformed;
  const uint32_t n = put_nearest_first(w, p.walk_geometry, cam.position);
  for (uint8_t& st : w.pair_state) st = kUnknown;
  for (uint32_t i = 0; i < w.kept; ++i) w.map_state[i] = kUnknown;
  FrameCtx ctx{&w, &cam};
  const ViewMapSource source{frame_map, &ctx, frame_point};
  const Mesh mesh = one_mesh(w, n, w.corners, &w.view_tex[0], &source);
  return w.renderer.render(cam, draw_list(w, &mesh), 0, detail::render_band_to_player, &p);
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

struct PredictCtx {
  WalkPlay* w;
  int slot;  // the view slot being predicted
};

// Triangle t of a prediction: from its own view when it lies in front of
// it, else from the first other view it lies in front of (never the slot
// being predicted), through the view's border.
bool predict_map(void* ctx, uint32_t, uint32_t first, const Texture** tex, Homography* out) {
  const PredictCtx& c = *static_cast<const PredictCtx*>(ctx);
  const WalkPlay& w = *c.w;
  const uint32_t slot_i = first / 3u;
  const Vec3<Q16_16>* tri = w.geometry->triangle(slot_i);
  const uint8_t own = w.view_of[slot_i];
  int v = own != c.slot && own < w.params.views && w.view_ready[own] && in_front(w.view_cam[own], tri) ? own : -1;
  for (int u = 0; u < w.params.views && v < 0; ++u)
    if (u != c.slot && w.view_ready[u] && in_front(w.view_cam[u], tri)) v = u;
  if (v < 0) return false;
  *tex = &w.bordered[v];
  Camera from = w.view_cam[v];
  from.cx = Q16_16::from_raw(from.cx.raw() + static_cast<int32_t>(kBorder << 16));
  from.cy = Q16_16::from_raw(from.cy.raw() + static_cast<int32_t>(kBorder << 16));
  return plane_homography(w.pending_cam, from, tri, out) == Status::ok;
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
  for (uint32_t slot_i = 0; slot_i < w.params.slots; ++slot_i)
    if (p.walk_geometry.triangle(slot_i) != nullptr) put_triangle(w, 3 * n++, slot_i);
  PredictCtx ctx{&w, slot};
  const ViewMapSource source{predict_map, &ctx};
  const Mesh mesh = one_mesh(w, n, nullptr, &w.bordered[other], &source);
  PredictTarget target{&w.view_tex[slot]};
  constexpr uint32_t kGrey = 0x808080;
  const Status s = w.renderer.render(w.pending_cam, draw_list(w, &mesh), kGrey, predict_band, &target);
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
  const RenderConfig rc = render_config(h, w, c, 0);
  // Each allocation of setup() with its worst alignment slack; the caches
  // a larger workspace adds (spare_caches) are not needed.
  return sizeof(WalkPlay) + alignof(WalkPlay) + WalkGeometry::workspace_bytes(w.slots) + ImageDecoder::kWorkspaceBytes +
         render_workspace_size(rc) + 3u * w.slots * sizeof(uint16_t) + 4 + 2u * w.slots +
         w.slots * sizeof(uint16_t) + alignof(uint16_t) + w.views * (plane_bytes(w) + 4);
}

namespace detail {
extern const PlayerMode kWalkMode;
const PlayerMode kWalkMode{StreamMode::walkthrough, start, on_chunk, feed_limit};
}  // namespace detail

}  // namespace vds
