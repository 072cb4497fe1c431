// The model mode's picture (vds/model_view.h): a progressive mesh drawn
// shaded from an orbiting camera through the scanline renderer.
#include "vds/model_view.h"

#include "vds/fixed.h"
#include "vds/render_camera.h"

namespace vds {
namespace {

// The renderer's uint16 indices, which draw() takes from the mesh's own
// 16-bit corner table (MeshState::triangles16).
constexpr uint32_t kMaxPositions = 65535;
// Faces summed into a vertex normal (a bound on the walk, far above any
// real fan; 2^10 - 1 keeps the sum of 2^21-bounded terms within int32).
constexpr uint32_t kMaxFanFaces = 1023;
constexpr uint32_t kElevation = 238609294u;                // 20 degrees in 2^-32 turn
// Direction to the light in camera space (x right, y down, z forward), Q15:
// to the left, above and toward the viewer; about unit length.
constexpr int32_t kLightCam[3] = {-14746, -18022, -22938};
constexpr uint32_t kAmbientQ8 = 56;   // intensity without light, of 256
constexpr uint32_t kDiffuseQ8 = 200;  // added at normal incidence

// Q2.30 (rotations, unit vectors): the product of two, rounded to nearest.
constexpr int kQ30 = Q2_30::kFracBits;
constexpr int64_t kQ30Half = int64_t{1} << (kQ30 - 1);

int32_t mul_q30(int32_t a, int32_t b) { return static_cast<int32_t>((int64_t{a} * b + kQ30Half) >> kQ30); }

int32_t abs32(int32_t v) { return v < 0 ? -v : v; }

// The normal of vertex v: the sum of its fan's face normals, each the
// cross product of the face's edges from v, (a - v) x (b - v) with a and b
// the next and previous corners' vertices, i.e. the face's own
// (p1 - p0) x (p2 - p0) exactly, shifted right by `shift`. Walking the fan
// counter-clockwise, a face's b is the next face's a, so each face reads
// one new position. Product is int32_t when the grid has at most 15 bits
// (the products then fit), int64_t otherwise.
template <typename Product>
void fan_normal(const MeshState& mesh, const uint16_t* tri, const uint16_t* pos, uint32_t v, int shift, int32_t n[3]) {
  n[0] = n[1] = n[2] = 0;
  const uint32_t nc = 3 * mesh.triangle_count();
  const uint32_t c0 = mesh.vertex_corner(v);
  if (c0 >= nc) return;  // no faces
  const uint16_t* pv = pos + 3 * v;
  const uint16_t* pa = pos + 3 * tri[MeshState::next(c0)];
  int32_t a[3] = {pa[0] - pv[0], pa[1] - pv[1], pa[2] - pv[2]};
  uint32_t c = c0;
  for (uint32_t faces = 0; faces < kMaxFanFaces; ++faces) {
    const uint16_t* pb = pos + 3 * tri[MeshState::prev(c)];
    const int32_t b[3] = {pb[0] - pv[0], pb[1] - pv[1], pb[2] - pv[2]};
    n[0] += static_cast<int32_t>((Product{a[1]} * b[2] - Product{a[2]} * b[1]) >> shift);
    n[1] += static_cast<int32_t>((Product{a[2]} * b[0] - Product{a[0]} * b[2]) >> shift);
    n[2] += static_cast<int32_t>((Product{a[0]} * b[1] - Product{a[1]} * b[0]) >> shift);
    const int32_t o = mesh.opposite(MeshState::next(c));
    if (o < 0 || static_cast<uint32_t>(o) >= nc) break;
    c = MeshState::next(static_cast<uint32_t>(o));
    if (c == c0) break;
    a[0] = b[0];
    a[1] = b[1];
    a[2] = b[2];
  }
}

RenderConfig render_config(const ModelViewConfig& cfg, uint32_t max_vertices, uint32_t max_triangles) {
  RenderConfig rc;
  rc.width = cfg.width;
  rc.height = cfg.height;
  rc.band_height = cfg.band_height;
  rc.format = PixelFormat::rgb565;
  rc.depth = DepthFormat::d16;
  rc.vertex_cache = cfg.vertex_cache < max_vertices ? cfg.vertex_cache : max_vertices;
  rc.triangle_cache = cfg.triangle_cache < max_triangles ? cfg.triangle_cache : max_triangles;
  rc.setup_cache = cfg.setup_cache;
  return rc;
}

}  // namespace

size_t ModelView::workspace_bytes(const ModelViewConfig& cfg, uint32_t max_vertices, uint32_t max_triangles) {
  if (max_vertices == 0 || max_vertices > kMaxPositions || max_triangles == 0) return 0;
  const size_t render = render_workspace_size(render_config(cfg, max_vertices, max_triangles));
  if (render == 0) return 0;
  // Colours (4 bytes per vertex) and alignment padding; the positions and
  // triangles are the mesh's own.
  return render + size_t{4} * max_vertices + 8;
}

Status ModelView::init(const ModelViewConfig& cfg, Arena& arena, uint32_t max_vertices, uint32_t max_triangles) {
  ready_ = false;
  if (workspace_bytes(cfg, max_vertices, max_triangles) == 0) return Status::invalid_argument;
  cfg_ = cfg;
  colors_ = arena.alloc_array<uint32_t>(max_vertices);
  if (!colors_) return Status::workspace_too_small;
  const Status s = renderer_.init(render_config(cfg, max_vertices, max_triangles), arena);
  if (s != Status::ok) return s;
  cap_v_ = max_vertices;
  cap_t_ = max_triangles;
  ready_ = true;
  return Status::ok;
}

Status ModelView::camera(const MeshState& mesh, uint16_t angle, Camera* out, uint8_t* grid_shift,
                         Vec3<Q16_16>* grid_origin) const {
  const uint32_t nv = mesh.vertex_count();
  const int bits = mesh.bits();
  if (!ready_ || nv == 0 || bits < 2 || bits > 16) return Status::invalid_argument;
  const uint16_t* pos = mesh.positions();
  // Camera basis (rows: right, down, forward) in Q2.30.
  const uint32_t theta = static_cast<uint32_t>(angle) << 16;
  const int32_t st = sin_q2_30(theta).raw(), ct = cos_q2_30(theta).raw();
  const int32_t sp = sin_q2_30(kElevation).raw(), cp = cos_q2_30(kElevation).raw();
  const int32_t view_rows[3][3] = {{ct, 0, -st},
                                   {mul_q30(sp, st), -cp, mul_q30(sp, ct)},
                                   {-mul_q30(cp, st), -sp, -mul_q30(cp, ct)}};
  // Those rows act on view axes (y up); the grid's axes reach them by a
  // rotation that takes the stream's up axis to y: view axis k is
  // sign[k] times grid axis axis[k], so rows = view_rows x that rotation.
  static constexpr int8_t kAxis[6][3] = {{0, 1, 2}, {0, 2, 1}, {1, 0, 2}, {0, 1, 2}, {0, 2, 1}, {1, 0, 2}};
  static constexpr int8_t kSign[6][3] = {{1, 1, 1}, {1, 1, -1}, {-1, 1, 1}, {-1, -1, 1}, {1, -1, 1}, {1, -1, 1}};
  const uint32_t u = static_cast<uint32_t>(cfg_.up) < 6 ? static_cast<uint32_t>(cfg_.up) : 0;
  int32_t rows[3][3];
  for (int i = 0; i < 3; ++i)
    for (int k = 0; k < 3; ++k) rows[i][kAxis[u][k]] = kSign[u][k] * view_rows[i][k];
  Camera& cam = *out;
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j) cam.rotation.m[i][j] = Q2_30::from_raw(rows[i][j]);
  // The centre of projection: D units back along the forward axis.
  // (Q2.30 x Q16.16 -> Q16.16: drop the rotation's fraction bits.)
  cam.position.x = Q16_16::from_raw(static_cast<int32_t>((-rows[2][0] * int64_t{kModelViewDistanceQ16}) >> kQ30));
  cam.position.y = Q16_16::from_raw(static_cast<int32_t>((-rows[2][1] * int64_t{kModelViewDistanceQ16}) >> kQ30));
  cam.position.z = Q16_16::from_raw(static_cast<int32_t>((-rows[2][2] * int64_t{kModelViewDistanceQ16}) >> kQ30));
  // Focal length one frame height: a point 1 unit from the centre, on the
  // near side, lands within 0.46 frame heights of the middle.
  const int32_t focal = int32_t{cfg_.height} * 65536;
  cam.fx = cam.fy = Q16_16::from_raw(focal < kCameraMinFocalPx * 65536 ? kCameraMinFocalPx * 65536 : focal);
  cam.cx = Q16_16::from_raw(int32_t{cfg_.width} << 15);
  cam.cy = Q16_16::from_raw(int32_t{cfg_.height} << 15);
  cam.near_z = Q16_16::from_raw(65536 / 2);
  cam.far_z = Q16_16::from_raw(8 * 65536);

  // The current bounding box: its centre is put at the origin.
  uint32_t lo[3] = {65535, 65535, 65535}, hi[3] = {0, 0, 0};
  for (uint32_t v = 0; v < nv; ++v)
    for (int a = 0; a < 3; ++a) {
      const uint32_t p = pos[3 * v + a];
      if (p < lo[a]) lo[a] = p;
      if (p > hi[a]) hi[a] = p;
    }
  // World positions, read by the renderer from the decoder's grid: 2^bits
  // grid steps = 2 units, i.e. (2 g - (lo + hi)) 2^(16 - bits) in Q16.16.
  const int up = 16 - bits;
  *grid_shift = static_cast<uint8_t>(up + 1);
  *grid_origin = {Q16_16::from_raw(-static_cast<int32_t>((lo[0] + hi[0]) << up)),
                  Q16_16::from_raw(-static_cast<int32_t>((lo[1] + hi[1]) << up)),
                  Q16_16::from_raw(-static_cast<int32_t>((lo[2] + hi[2]) << up))};
  return Status::ok;
}

Status ModelView::draw(const MeshState& mesh, uint16_t angle, BandSink sink, void* ctx, const MeshColorsSurface* colors,
                       Filter filter) {
  const uint32_t nv = mesh.vertex_count(), nt = mesh.triangle_count();
  if (!ready_ || nv == 0 || nv > cap_v_ || nt > cap_t_) return Status::invalid_argument;
  const int bits = mesh.bits();
  if (bits < 2 || bits > 16) return Status::invalid_argument;
  const uint16_t* pos = mesh.positions();
  const uint16_t* tri = mesh.triangles16();
  if (tri == nullptr) return Status::invalid_argument;

  Camera cam;
  uint8_t grid_shift = 0;
  Vec3<Q16_16> grid_origin{};
  const Status cs = camera(mesh, angle, &cam, &grid_shift, &grid_origin);
  if (cs != Status::ok) return cs;
  int32_t rows[3][3];
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j) rows[i][j] = cam.rotation.m[i][j].raw();
  // The light in world space: R^T applied to its camera-space direction (Q15).
  int32_t light[3];
  for (int a = 0; a < 3; ++a)
    light[a] = static_cast<int32_t>(
        (int64_t{kLightCam[0]} * rows[0][a] + int64_t{kLightCam[1]} * rows[1][a] + int64_t{kLightCam[2]} * rows[2][a]) >>
        30);

  for (uint32_t i = 0; i < 3 * nt; ++i)
    if (tri[i] >= nv) return Status::invalid_argument;

  // Vertex colours from vertex normals: each the sum of the cross products
  // of the faces in the vertex's fan, each brought to at most 2^21 per
  // component (an arithmetic shift by 2 (bits - 10)), over at most
  // kMaxFanFaces faces, so a sum stays below 2^31. The fan is walked in the
  // corner table (one fan per vertex, from its first face on a boundary),
  // so no per-vertex sums are stored.
  const int shift = bits > 10 ? 2 * (bits - 10) : 0;
  const uint32_t nlit = colors != nullptr ? 0 : nv;  // mesh colors are drawn unlit
  const uint32_t base_rgb[3] = {(cfg_.surface_rgb >> 16) & 255, (cfg_.surface_rgb >> 8) & 255, cfg_.surface_rgb & 255};
  for (uint32_t v = 0; v < nlit; ++v) {
    int32_t n[3];
    if (bits <= 15)
      fan_normal<int32_t>(mesh, tri, pos, v, shift, n);
    else
      fan_normal<int64_t>(mesh, tri, pos, v, shift, n);
    // Down to 15 bits a component (arithmetic shift), so the squared length
    // fits 32 bits and |n . l| <= |n| 2^15 (Cauchy-Schwarz) fits after >> 15.
    const uint32_t m = static_cast<uint32_t>(abs32(n[0]) | abs32(n[1]) | abs32(n[2]));
    const int down = m >= 32768 ? 17 - __builtin_clz(m) : 0;
    for (int32_t& x : n) x >>= down;
    const uint32_t len = isqrt32(static_cast<uint32_t>(n[0] * n[0]) + static_cast<uint32_t>(n[1] * n[1]) +
                                 static_cast<uint32_t>(n[2] * n[2]));
    uint32_t intensity = kAmbientQ8;
    if (len != 0) {
      int64_t dot = int64_t{n[0]} * light[0] + int64_t{n[1]} * light[1] + int64_t{n[2]} * light[2];
      if (dot < 0) dot = -dot;  // two-sided: orientation of the input is not assumed
      const uint32_t cosine = static_cast<uint32_t>(dot >> 15);  // |n| cos, <= len
      intensity += (cosine * kDiffuseQ8) / len;
    }
    uint32_t rgb = 0;
    for (int k = 0; k < 3; ++k) {
      uint32_t ch = (base_rgb[k] * intensity) >> 8;
      if (ch > 255) ch = 255;
      rgb = (rgb << 8) | ch;
    }
    colors_[v] = rgb;
  }

  Mesh m;
  m.indices = tri;
  m.num_triangles = nt;
  m.shading = Shading::gouraud;
  m.cull = Cull::none;
  m.colors = colors_;
  if (colors != nullptr) {
    m.shading = Shading::mesh_colors;
    m.surface = colors;
    m.filter = filter;
  }
  DrawList list;
  list.grid = pos;
  list.grid_shift = grid_shift;
  list.grid_origin = grid_origin;
  list.num_positions = nv;
  list.meshes = &m;
  list.num_meshes = 1;
  return renderer_.render(cam, list, cfg_.background_rgb, sink, ctx);
}

namespace {

// Most triangles a level with v vertices can have (v >= base vertices).
uint32_t triangles_for(const MeshHeader& h, uint32_t v) {
  const uint64_t t = uint64_t{h.base_triangles} + 2 * uint64_t{v - h.base_vertices};
  return t < h.triangles ? static_cast<uint32_t>(t) : h.triangles;
}

// Decoder and view bytes for v vertices and t triangles (and a tail's
// border of that many edges); SIZE_MAX if they cannot be had.
size_t client_bytes(const MeshHeader& h, const ModelViewConfig& cfg, uint32_t v, uint32_t t, uint32_t tail_border) {
  const size_t dec = MeshDecoder::workspace_bytes(v, t, h.base_triangles, h.coder, tail_border);
  const size_t view = ModelView::workspace_bytes(cfg, v, t);
  if (dec == SIZE_MAX || view == 0 || dec > SIZE_MAX - view) return SIZE_MAX;
  return dec + view;
}

// The same for the split levels up to v vertices.
size_t model_bytes(const MeshHeader& h, const ModelViewConfig& cfg, uint32_t v) {
  return client_bytes(h, cfg, v, triangles_for(h, v), 0);
}

}  // namespace

Status plan_model_capacity(const MeshHeader& h, const ModelViewConfig& cfg, size_t bytes, ModelCapacity* out) {
  if (out == nullptr) return Status::invalid_argument;
  *out = ModelCapacity{};
  if (ModelView::workspace_bytes(cfg, 1, 1) == 0 || h.base_vertices == 0 || h.base_vertices > h.vertices ||
      h.base_triangles > h.triangles)
    return Status::invalid_argument;
  if (h.base_vertices > kMaxPositions) return Status::unsupported_feature;
  const size_t base = model_bytes(h, cfg, h.base_vertices);
  if (base > bytes) {
    out->bytes = base;
    return Status::workspace_too_small;
  }
  // A version-2 stream's tail rebuilds the whole mesh with its hole-closing
  // dummies, its contexts and its border: all of it, or the split levels.
  // (mesh_header_from_bytes bounds both sums far below 2^32.)
  if (h.tail() && uint64_t{h.vertices} + h.tail_dummy_vertices <= kMaxPositions) {
    const uint32_t tv = h.vertices + h.tail_dummy_vertices;
    const uint32_t tt = h.triangles + h.tail_dummy_triangles;
    const size_t need = client_bytes(h, cfg, tv, tt, h.tail_max_border);
    if (need <= bytes) {
      out->vertices = tv;
      out->triangles = tt;
      out->bytes = need;
      return Status::ok;
    }
  }
  // The largest vertex count that fits: the bytes grow with the count.
  uint32_t lo = h.base_vertices;
  uint32_t hi = h.vertices < kMaxPositions ? h.vertices : kMaxPositions;
  while (lo < hi) {
    const uint32_t mid = lo + (hi - lo + 1) / 2;
    if (model_bytes(h, cfg, mid) <= bytes)
      lo = mid;
    else
      hi = mid - 1;
  }
  out->vertices = lo;
  out->triangles = triangles_for(h, lo);
  out->bytes = model_bytes(h, cfg, lo);
  return Status::ok;
}

Status start_model(Arena& arena, const uint8_t* mshh, uint32_t size, const ModelViewConfig& cfg, MeshDecoder& mesh,
                   ModelView& view, ModelCapacity* cap) {
  ModelCapacity local;
  ModelCapacity* c = cap != nullptr ? cap : &local;
  *c = ModelCapacity{};
  MeshHeader h;
  Status s = mesh_header_from_bytes(mshh, size, &h);
  if (s != Status::ok) return s;
  ModelViewConfig vc = cfg;
  vc.up = h.up;
  if ((s = plan_model_capacity(h, vc, arena.remaining(), c)) != Status::ok) return s;
  if ((s = mesh.init(arena, c->vertices, c->triangles)) != Status::ok) return s;
  return view.init(vc, arena, c->vertices, c->triangles);
}

}  // namespace vds
