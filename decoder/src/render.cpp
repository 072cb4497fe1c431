// The renderer's frame and band driver (vds/render.h): validation, the
// projected-vertex cache, band clearing, per-triangle trivial rejection and
// the choice between the direct path and clipping, and the display callback.
#include "vds/render.h"

#include <cstring>

#include "render_internal.h"
#include "vds/config.h"
#include "vds/render_raster.h"

namespace vds {

namespace {

using detail::CachedVertex;
using detail::ClipVertex;
using detail::ScreenVertex;

constexpr size_t kAlignSlack = 3;  // 4-byte aligned allocations
constexpr uint32_t kMaxSetupCache = 4096;

// Bytes of one setup_cache entry (a multiple of its alignment).
size_t setup_entry_bytes() {
  const size_t a = detail::prepared_polygon_align();
  return (detail::prepared_polygon_bytes() + a - 1) / a * a;
}

bool format_compiled(PixelFormat f) {
  const int bit = 1 << static_cast<int>(f);
  return static_cast<uint8_t>(f) <= 1 && (VDS_CONFIG_RENDER_OUTPUT_FORMATS & bit) != 0;
}
bool depth_compiled(DepthFormat d) {
  const int bit = 1 << static_cast<int>(d);
  return static_cast<uint8_t>(d) <= 1 && (VDS_CONFIG_RENDER_DEPTH_FORMATS & bit) != 0;
}

Status check_config(const RenderConfig& c) {
  if (c.width < 1 || c.width > kRenderMaxSize || c.height < 1 || c.height > kRenderMaxSize) {
    return Status::invalid_argument;
  }
  if (c.band_height < 1 || c.band_height > c.height) return Status::invalid_argument;
  if (static_cast<uint8_t>(c.format) > 1 || static_cast<uint8_t>(c.depth) > 1) return Status::invalid_argument;
  if (!format_compiled(c.format) || !depth_compiled(c.depth)) return Status::unsupported_feature;
  if (c.vertex_cache > 65536 || c.triangle_cache > (1u << 24) || c.setup_cache > kMaxSetupCache) {
    return Status::invalid_argument;
  }
  if (c.target) {
    const uint32_t row = static_cast<uint32_t>(c.width) * static_cast<uint32_t>(bytes_per_pixel(c.format));
    if (c.target_stride < row) return Status::invalid_argument;
    if (c.format == PixelFormat::rgb565 &&
        ((reinterpret_cast<uintptr_t>(c.target) & 1) != 0 || (c.target_stride & 1) != 0)) {
      return Status::invalid_argument;
    }
  }
  return Status::ok;
}

Status check_texture(const Texture* t) {
  if (!t || !t->texels) return Status::malformed;
  if (static_cast<uint8_t>(t->format) > 2 || static_cast<uint8_t>(t->address) > 1) return Status::invalid_argument;
  if (!(VDS_CONFIG_RENDER_TEXTURE_FORMATS & (1 << static_cast<int>(t->format)))) return Status::unsupported_feature;
  if (t->width < 1 || t->width > kTextureMaxSize || t->height < 1 || t->height > kTextureMaxSize) {
    return Status::invalid_argument;
  }
  if (t->stride < t->width) return Status::invalid_argument;
  if (t->apron && (t->format == TexFormat::ycbcr420 || t->stride < static_cast<uint32_t>(t->width) + 1)) {
    return Status::invalid_argument;
  }
  if (t->format == TexFormat::ycbcr420) {
    if (!t->cb || !t->cr) return Status::malformed;
    if (t->chroma_stride < static_cast<uint32_t>((t->width + 1) / 2)) return Status::invalid_argument;
  }
  return Status::ok;
}

// The corners of all of m's faces (below 2^31: check_list bounds the faces).
uint32_t mesh_corners(const Mesh& m) {
  if (!m.corners) return 3 * m.num_triangles;
  uint32_t n = 0;
  for (uint32_t t = 0; t < m.num_triangles; ++t) n += m.corners[t];
  return n;
}

Status check_list(const DrawList& list) {
  if (list.num_positions > 65536) return Status::malformed;
  if (list.num_positions && (list.positions == nullptr) == (list.grid == nullptr)) return Status::invalid_argument;
  if (list.grid_shift > 15) return Status::invalid_argument;
  if (list.num_meshes && !list.meshes) return Status::invalid_argument;
  for (uint32_t i = 0; i < list.num_meshes; ++i) {
    const Mesh& m = list.meshes[i];
    if (static_cast<uint8_t>(m.shading) > 4 || static_cast<uint8_t>(m.filter) > 2 || static_cast<uint8_t>(m.cull) > 2) {
      return Status::invalid_argument;
    }
    if (m.num_triangles == 0) continue;
    if (!m.indices || m.num_triangles > 0x7FFFFFFFu / kMaxFaceCorners) return Status::malformed;
    if (m.corners && m.shading == Shading::mesh_colors) return Status::invalid_argument;
    if (m.corners)
      for (uint32_t t = 0; t < m.num_triangles; ++t)
        if (m.corners[t] < 3 || m.corners[t] > kMaxFaceCorners) return Status::malformed;
    const uint32_t count = mesh_corners(m);
    for (uint32_t k = 0; k < count; ++k) {
      if (m.indices[k] >= list.num_positions) return Status::malformed;
    }
    if (m.shading == Shading::gouraud && !m.colors) return Status::malformed;
    if (m.shading == Shading::texture && !m.uvs) return Status::malformed;
    if (m.shading == Shading::mesh_colors &&
        (!m.surface || !m.surface->face || !m.surface->y || !m.surface->cb || !m.surface->cr))
      return Status::malformed;
    if (m.shading == Shading::view_mapped && m.views && !m.views->map) return Status::malformed;
    if (m.shading == Shading::texture || m.shading == Shading::view_mapped) {
      const Status st = check_texture(m.texture);
      if (st != Status::ok) return st;
    }
  }
  return Status::ok;
}

int num_attribs(Shading s) {
  switch (s) {
    case Shading::gouraud: return 3;
    case Shading::texture: return 2;
    case Shading::mesh_colors: return 2;
    default: return 0;
  }
}

// n words of value v. Every band is cleared whole, colour and depth, so on
// ARM (Thumb-2: Cortex-M3/M4/M7) this uses multiple-register stores, 32
// bytes in four instructions (gcc makes 12 instructions per 32 bytes of the
// C++ loop below: 2.4 instructions per pixel of a frame with 32-bit depth
// instead of 0.9); elsewhere eight word stores per iteration. Same bytes.
void fill_words(uint32_t* p, uint32_t v, size_t n) {
#if defined(__arm__) && defined(__thumb2__)
  if (size_t blocks = n / 8) {
    register uint32_t a asm("r4") = v;
    register uint32_t b asm("r5") = v;
    register uint32_t c asm("r6") = v;
    register uint32_t d asm("r8") = v;
    asm volatile(
        "1:\n\t"
        "stmia %[p]!, {%[a], %[b], %[c], %[d]}\n\t"
        "stmia %[p]!, {%[a], %[b], %[c], %[d]}\n\t"
        "subs %[k], %[k], #1\n\t"
        "bne 1b"
        : [p] "+r"(p), [k] "+r"(blocks)
        : [a] "r"(a), [b] "r"(b), [c] "r"(c), [d] "r"(d)
        : "cc", "memory");
    n %= 8;
  }
#endif
  for (; n >= 8; n -= 8, p += 8) {
    p[0] = v;
    p[1] = v;
    p[2] = v;
    p[3] = v;
    p[4] = v;
    p[5] = v;
    p[6] = v;
    p[7] = v;
  }
  for (; n; --n) *p++ = v;
}

// Fills bytes [p, p + n) with the 4-byte pattern `v` (its low byte first in
// memory order of a little- or big-endian word store alike, since every use
// repeats the pattern with a period dividing 4 bytes); unaligned ends by bytes.
void fill_pattern(uint8_t* p, uint32_t v, size_t n) {
  uint8_t b[4];
  std::memcpy(b, &v, 4);
  size_t k = 0;
  for (; k < n && (reinterpret_cast<uintptr_t>(p + k) & 3u) != 0; ++k) p[k] = b[k & 3];
  // The pattern continues at phase k & 3: rotate the word to match.
  uint8_t r[4] = {b[k & 3], b[(k + 1) & 3], b[(k + 2) & 3], b[(k + 3) & 3]};
  uint32_t w;
  std::memcpy(&w, r, 4);
  const size_t words = (n - k) / 4;
  fill_words(reinterpret_cast<uint32_t*>(p + k), w, words);
  for (size_t i = k + words * 4; i < n; ++i) p[i] = b[i & 3];
}

// Fills the band with the clear colour and zeroes its depth.
void clear_band(const detail::BandTarget& b, uint32_t rgb) {
  const int32_t rows = b.y1 - b.y0;
  const size_t row_bytes = static_cast<size_t>(b.width) * static_cast<size_t>(bytes_per_pixel(b.format));
  if (b.format == PixelFormat::rgb565) {
    const uint16_t c = static_cast<uint16_t>(((((rgb >> 16) & 255) * 249 + 1014) >> 11) << 11 |
                                             ((((rgb >> 8) & 255) * 253 + 505) >> 10) << 5 |
                                             (((rgb & 255) * 249 + 1014) >> 11));
    uint32_t v;
    const uint16_t two[2] = {c, c};
    std::memcpy(&v, two, 4);
    if (b.color_stride == row_bytes) {
      fill_pattern(b.color, v, row_bytes * static_cast<size_t>(rows));
    } else {
      for (int32_t r = 0; r < rows; ++r) fill_pattern(b.color + static_cast<uint32_t>(r) * b.color_stride, v, row_bytes);
    }
  } else {
    // Three bytes per pixel: the first row by pixels, the others copied.
    uint8_t* first = b.color;
    for (int32_t x = 0; x < b.width; ++x) {
      first[3 * x] = static_cast<uint8_t>(rgb >> 16);
      first[3 * x + 1] = static_cast<uint8_t>(rgb >> 8);
      first[3 * x + 2] = static_cast<uint8_t>(rgb);
    }
    for (int32_t r = 1; r < rows; ++r) std::memcpy(b.color + static_cast<uint32_t>(r) * b.color_stride, first, row_bytes);
  }
  fill_pattern(static_cast<uint8_t*>(b.depth), 0,
               static_cast<size_t>(rows) * static_cast<size_t>(b.width) * static_cast<size_t>(bytes_per_depth(b.depth_format)));
}

}  // namespace

namespace detail {

// State of one frame: the camera, the vertex cache and the per-triangle logic.
struct RenderFrame {
  Renderer& r;
  const DrawList& list;
  FrameCamera fc;
  uint32_t cached = 0;
  // The set-up cache (Renderer::setup_*): live entries [0, live) sorted by
  // tag, the band's new ones at [cap - fresh, cap) (the latest lowest), the
  // cursor of the band's walk through the live ones, and free slots.
  // Slots [unused, cap) have not been taken yet this frame (no free list to
  // fill per frame).
  uint32_t live = 0, fresh = 0, cursor = 0, free_slots = 0, unused = 0;
  int32_t live_end = 0;  // the first row past the live polygon that ends first

  // World position of vertex i.
  Vec3<Q16_16> world(uint32_t i) const {
    if (list.positions != nullptr) return list.positions[i];
    const uint16_t* g = list.grid + 3 * i;
    const Vec3<Q16_16>& o = list.grid_origin;
    const int s = list.grid_shift;
    return {Q16_16::from_raw(sat_s32((int64_t{g[0]} << s) + o.x.raw())),
            Q16_16::from_raw(sat_s32((int64_t{g[1]} << s) + o.y.raw())),
            Q16_16::from_raw(sat_s32((int64_t{g[2]} << s) + o.z.raw()))};
  }

  // Camera-space vertex i (no attributes).
  ClipVertex camera_vertex(uint32_t i) const {
    const Vec3<Q16_16> p = camera_transform(*fc.cam, world(i));
    ClipVertex v{};
    v.x = p.x.raw();
    v.y = p.y.raw();
    v.z = p.z.raw();
    return v;
  }

  // Outcode of vertex i and, unless the result has kNoProjection, its
  // screen position and q. Every vertex in front of the near plane whose
  // projection fits is projected, clipped or not: its position then bounds
  // the rows a clipped triangle can reach (clipping at the far plane and the
  // guard band only cuts the triangle's own screen image).
  uint8_t project(uint32_t i, CachedVertex* out) const {
    const ClipVertex v = camera_vertex(i);
    uint8_t oc = outcode(fc, v);
    if (oc & kOutNear) return static_cast<uint8_t>(oc | kNoProjection);
    const Vec3<Q16_16> p{Q16_16::from_raw(v.x), Q16_16::from_raw(v.y), Q16_16::from_raw(v.z)};
    if (!camera_project(*fc.cam, p, &out->x, &out->y)) return static_cast<uint8_t>(oc | kNoProjection);
    out->q = depth_q(fc, v.z);
    return oc;
  }

  // Projects the vertices below the cache's size: every one when the
  // meshes name at least as many vertices as that (a mesh's vertices are
  // shared by its triangles), else only those a triangle names (a draw list
  // may hold many positions no mesh draws this frame).
  void fill_cache() {
    const uint32_t n = list.num_positions < r.cfg_.vertex_cache ? list.num_positions : r.cfg_.vertex_cache;
    uint8_t* const oc = r.cache_outcode_;
    cached = n;
    uint64_t named = 0;
    for (uint32_t mi = 0; mi < list.num_meshes; ++mi) named += mesh_corners(list.meshes[mi]);
    if (named >= n) {
      for (uint32_t i = 0; i < n; ++i) oc[i] = project(i, &r.cache_[i]);
      return;
    }
    for (uint32_t i = 0; i < n; ++i) oc[i] = kUnprojected;
    for (uint32_t mi = 0; mi < list.num_meshes; ++mi) {
      const Mesh& m = list.meshes[mi];
      const uint32_t count = mesh_corners(m);
      for (uint32_t k = 0; k < count; ++k) {
        const uint32_t i = m.indices[k];
        if (i < n && oc[i] == kUnprojected) oc[i] = project(i, &r.cache_[i]);
      }
    }
  }

  // The band range of every face the triangle cache holds, from the same
  // test draw_mesh applies per band: [1, 0] (empty) for a face outside a
  // clip plane, [0, last band] when its vertices are not all projected.
  void fill_triangle_bands() {
    const uint32_t cap = r.cfg_.triangle_cache;
    uint32_t g = 0;
    for (uint32_t mi = 0; mi < list.num_meshes && g < cap; ++mi) {
      const Mesh& m = list.meshes[mi];
      const uint16_t* idx = m.indices;
      for (uint32_t t = 0; t < m.num_triangles && g < cap; ++t, ++g) {
        const int n = m.corners ? m.corners[t] : 3;
        if (n == 3) {
          face_bands<3>(m, idx, g);
        } else {
          face_bands<4>(m, idx, g);
        }
        idx += n;
      }
    }
  }
  // The least and greatest of field F (x or y) over N vertices.
  template <int N, int32_t CachedVertex::*F>
  static void extent(const CachedVertex* v, int32_t* lo, int32_t* hi) {
    int32_t l = v[0].*F, h = l;
#pragma GCC unroll 4
    for (int k = 1; k < N; ++k) {
      l = v[k].*F < l ? v[k].*F : l;
      h = v[k].*F > h ? v[k].*F : h;
    }
    *lo = l;
    *hi = h;
  }

  // Triangle cache entry g: the bands of the face of N corners idx[0..N).
  // (Each per-corner loop below has a constant count, unrolled: set-up
  // bound scenes visit many faces.)
  template <int N>
  void face_bands(const Mesh& m, const uint16_t* idx, uint32_t g) {
    const int32_t bh = r.cfg_.band_height;
    uint16_t first = 0, last = static_cast<uint16_t>((r.cfg_.height - 1) / bh);
    // A vertex past the vertex cache is projected here for its face
    // alone (and again in the bands that draw it).
    CachedVertex cv[N];
    uint8_t all = kOutAll, any = 0;
#pragma GCC unroll 4
    for (int k = 0; k < N; ++k) {
      const uint8_t oc = fetch(idx[k], &cv[k]);
      all &= oc;
      any |= oc;
    }
    if (all & kOutAll) {
      first = 1;
      last = 0;
    } else if (!(any & kNoProjection)) {
      int32_t lo, hi;
      extent<N, &CachedVertex::y>(cv, &lo, &hi);
      const int32_t margin = any ? 256 : 0;
      lo -= margin;
      hi += margin;
      // Rows [raster_row(lo), raster_row(hi)), clamped to the screen.
      int32_t r0 = raster_row(lo), r1 = raster_row(hi);
      r0 = r0 < 0 ? 0 : r0;
      r1 = r1 > r.cfg_.height ? r.cfg_.height : r1;
      if (r0 >= r1) {
        first = 1;
        last = 0;
      } else {
        first = static_cast<uint16_t>(r0 / bh);
        last = static_cast<uint16_t>((r1 - 1) / bh);
        if (any == 0 && !drawable<N>(m, cv)) {
          // Unclipped and off screen sideways, facing away or of zero
          // area: no band draws it (draw_mesh would reject it in each
          // of its bands, counting it culled there when on screen).
          if (on_screen_x<N>(cv)) {
            r.stats_.culled += static_cast<uint32_t>(last - first) + 1;
          }
          first = 1;
          last = 0;
        }
      }
    }
    r.tri_bands_[2 * g] = first;
    r.tri_bands_[2 * g + 1] = last;
  }

  // Whether an unclipped face of N corners reaches the screen's columns,
  // as prepare_polygon tests them (pixel centres inside its box).
  template <int N>
  bool on_screen_x(const CachedVertex* v) const {
    int32_t xlo, xhi;
    extent<N, &CachedVertex::x>(v, &xlo, &xhi);
    return raster_row(xhi) > 0 && raster_row(xlo) < r.cfg_.width;
  }

  // Whether an unclipped face of N corners can draw anything: on screen
  // sideways, facing the way the mesh draws and of non-zero area (the same
  // products as prepare_polygon's fan: its signed area, and some fan
  // triangle's).
  template <int N>
  bool drawable(const Mesh& m, const CachedVertex* v) const {
    int64_t area = 0;
    bool some = false;
#pragma GCC unroll 4
    for (int i = 1; i + 1 < N; ++i) {
      const int64_t a = int64_t{v[i].x - v[0].x} * (v[i + 1].y - v[0].y) - int64_t{v[i + 1].x - v[0].x} * (v[i].y - v[0].y);
      area += a;
      some = some || a != 0;
    }
    if (area == 0 || !some || (m.cull == Cull::back && area > 0) || (m.cull == Cull::front && area < 0)) return false;
    return on_screen_x<N>(v);
  }

  uint8_t fetch(uint32_t i, CachedVertex* out) {
    if (i < cached) {
      *out = r.cache_[i];
      return r.cache_outcode_[i];
    }
    ++r.stats_.reprojected;
    return project(i, out);
  }

  // Vertex i at corner k of its triangle.
  static void attributes(const Mesh& m, uint32_t i, int k, int32_t* a) {
    if (m.shading == Shading::mesh_colors) {
      // Barycentric weights of corners b and c in Q16.16 (the set-up scales them by R).
      a[0] = k == 1 ? 65536 : 0;
      a[1] = k == 2 ? 65536 : 0;
      a[2] = 0;
    } else if (m.shading == Shading::texture) {
      a[0] = m.uvs[i].u.raw();
      a[1] = m.uvs[i].v.raw();
      a[2] = 0;
    } else if (m.shading == Shading::gouraud) {
      const uint32_t c = m.colors[i];
      a[0] = static_cast<int32_t>(((c >> 16) & 255) << 8);  // Q8.8
      a[1] = static_cast<int32_t>(((c >> 8) & 255) << 8);
      a[2] = static_cast<int32_t>((c & 255) << 8);
    } else {
      a[0] = a[1] = a[2] = 0;
    }
  }

  // Triangle cache entry g: the bands of rows [r0, r1) (clamped to the screen).
  void set_triangle_rows(uint32_t g, int32_t r0, int32_t r1) {
    const int32_t bh = r.cfg_.band_height;
    r0 = r0 < 0 ? 0 : r0;
    r1 = r1 > r.cfg_.height ? r.cfg_.height : r1;
    if (r0 >= r1) {
      r.tri_bands_[2 * g] = 1;
      r.tri_bands_[2 * g + 1] = 0;
    } else {
      r.tri_bands_[2 * g] = static_cast<uint16_t>(r0 / bh);
      r.tri_bands_[2 * g + 1] = static_cast<uint16_t>((r1 - 1) / bh);
    }
  }

  detail::PreparedPolygon* setup_entry(uint32_t slot) const {
    return reinterpret_cast<detail::PreparedPolygon*>(r.setups_ + size_t{slot} * r.setup_bytes_);
  }

  // Draws polygon sv[0..n) of triangle number g. A polygon that reaches
  // below the band is set up into its setup_cache entry, for later bands.
  // A clipped polygon is the same in every band: its rows replace the
  // widened estimate of the triangle cache, so that later bands skip it with
  // two compares instead of clipping it again.
  void draw(const BandTarget& band, const MaterialCtx& mat, const ScreenVertex* sv, int n, uint32_t g, bool clipped) {
    const uint32_t scap = r.cfg_.setup_cache;
    int32_t ymin = sv[0].y, ymax = sv[0].y;
    for (int k = 1; k < n; ++k) {
      ymin = sv[k].y < ymin ? sv[k].y : ymin;
      ymax = sv[k].y > ymax ? sv[k].y : ymax;
    }
    if (clipped && g < r.cfg_.triangle_cache) set_triangle_rows(g, raster_row(ymin), raster_row(ymax));
    // Kept for later bands when it reaches below this one and a slot is free
    // (first come, first served: taking the slot of a kept polygon that ends
    // sooner was measured to set up more polygons, not fewer).
    const bool keep = (free_slots != 0 || unused < scap) && g < UINT32_MAX - 1 && raster_row(ymax) > band.y1;
    if (raster_row(ymax) <= band.y0 || raster_row(ymin) >= band.y1) {
      // Only a clipped polygon gets here with rows that miss the band (it is
      // visited in every band its unclipped triangle may reach): no set-up
      // for this band (draw_polygon would set it up and draw nothing).
      // A clipped polygon below the band waits for its first band when the
      // triangle cache (narrowed above) brings it back there: clipping it
      // again costs less than holding a slot until then.
      if (!keep || (clipped && g < r.cfg_.triangle_cache)) return;
    } else if (!keep) {
      draw_polygon(band, mat, sv, n, r.stats_);
      return;
    }
    const uint16_t slot = free_slots != 0 ? r.setup_free_[--free_slots] : static_cast<uint16_t>(unused++);
    detail::PreparedPolygon* pp = setup_entry(slot);
    prepare_polygon(detail::PolygonTarget{band.width, band.height, band.format, band.depth_format}, mat, sv, n, pp);
    ++fresh;
    r.setup_tags_[scap - fresh] = g + 1;
    r.setup_slots_[scap - fresh] = slot;
    ++r.stats_.setups;
    draw_prepared(band, *pp, r.stats_);
  }

  // Frees the entries whose polygons end in the band that ends at row y1
  // and merges the band's new entries into the sorted live ones.
  void end_band(int32_t y1) {
    cursor = 0;
    if (fresh == 0 && live_end > y1) return;  // nothing new, nothing ends
    const uint32_t scap = r.cfg_.setup_cache;
    uint32_t* const tags = r.setup_tags_;
    uint16_t* const slots = r.setup_slots_;
    uint32_t* const out_tags = r.setup_tags2_;
    uint16_t* const out_slots = r.setup_slots2_;
    uint32_t a = 0, b = 0, n = 0;
    live_end = INT32_MAX;
    while (a < live || b < fresh) {
      // Live tags ascend from index 0, new ones from index scap - 1 down.
      const bool from_live = b == fresh || (a < live && tags[a] < tags[scap - 1 - b]);
      const uint32_t i = from_live ? a++ : scap - 1 - b++;
      const int32_t end = prepared_row_end(*setup_entry(slots[i]));
      if (end <= y1) {
        r.setup_free_[free_slots++] = slots[i];
      } else {
        live_end = end < live_end ? end : live_end;
        out_tags[n] = tags[i];
        out_slots[n] = slots[i];
        ++n;
      }
    }
    live = n;
    fresh = 0;
    // The merged arrays become the live ones.
    r.setup_tags_ = out_tags;
    r.setup_slots_ = out_slots;
    r.setup_tags2_ = tags;
    r.setup_slots2_ = slots;
  }

  // Draws mesh m into the band; `first_tri` is the running index of its first
  // face (for the triangle cache), `band_index` the band's number. Meshes
  // of triangles take a loop of their own (three corners known: the
  // per-face loops unrolled, as set-up bound scenes need).
  void draw_mesh(const BandTarget& band, const Mesh& m, uint32_t first_tri, uint16_t band_index) {
    if (m.corners) {
      draw_faces<true>(band, m, first_tri, band_index);
    } else {
      draw_faces<false>(band, m, first_tri, band_index);
    }
  }

  template <bool kFaces>
  void draw_faces(const BandTarget& band, const Mesh& m, uint32_t first_tri, uint16_t band_index) {
    MaterialCtx mat{&m, num_attribs(m.shading), 0, 0, 3, r.cfg_.point_face_span};
    const uint32_t tcap = r.cfg_.triangle_cache;
    const uint16_t* const tb = r.tri_bands_;
    const uint32_t nt = m.num_triangles;
    const uint8_t* const corners = kFaces ? m.corners : nullptr;
    // Faces [0, tc_end) of the mesh are in the triangle cache.
    const uint32_t tc_end = first_tri >= tcap ? 0 : (tcap - first_tri < nt ? tcap - first_tri : nt);
    const uint16_t* next = m.indices;  // faces: the corners of the face after the last one drawn or skipped
    for (uint32_t t = 0; t < nt; ++t) {
      if (t < tc_end) {
        // Most faces miss a band: skip them in a loop of their own.
        const uint16_t* p = tb + 2 * size_t{first_tri + t};
        if (band_index < p[0] || band_index > p[1]) {
          do {
            if constexpr (kFaces) next += corners[t];
            ++t;
            p += 2;
          } while (t < tc_end && (band_index < p[0] || band_index > p[1]));
          if (t == nt) break;
        }
      }
      // Face t's corners.
      const uint16_t* idx = m.indices + 3 * size_t{t};
      int n = 3;
      if constexpr (kFaces) {
        n = corners[t];
        idx = next;
        next += n;
      }
      const uint32_t g = first_tri + t;
      mat.tri = t;
      mat.first = idx[0];
      mat.corners = n;
      if (cursor < live) {
        // Live tags ascend and so do the faces of a band's walk.
        const uint32_t* const tags = r.setup_tags_;
        while (cursor < live && tags[cursor] <= g) ++cursor;
        if (cursor < live && tags[cursor] == g + 1) {
          // Set up (and clipped) in an earlier band of this frame.
          draw_prepared(band, *setup_entry(r.setup_slots_[cursor]), r.stats_);
          ++cursor;
          continue;
        }
      }
      if (n == 3) {
        draw_face<3>(band, mat, idx, g);
      } else {
        draw_face<4>(band, mat, idx, g);
      }
    }
  }

  // Draws face g of N corners idx[0..N) into the band (unless it misses
  // it, lies outside a clip plane or cannot draw anything). Each
  // per-corner loop has a constant count, unrolled: set-up bound scenes
  // visit many faces.
  template <int N>
  void draw_face(const BandTarget& band, const MaterialCtx& mat, const uint16_t* idx, uint32_t g) {
    const Mesh& m = *mat.mesh;
    // A face misses the band when raster_row(ymax) <= y0 or
    // raster_row(ymin) >= y1, i.e. ymax <= 256 y0 + 128 or ymin >= 256 y1 - 127.
    const int32_t miss_below = band.y0 * 256 + 128;
    const int32_t miss_above = band.y1 * 256 - 127;
    const CachedVertex* const cache = r.cache_;
    CachedVertex cv[N];
    uint8_t all = kOutAll, any = 0;
    // Whether rows [lo, hi] (Q24.8) miss the band. Clipped vertices are
    // rounded on their own, so a clipped face's bound is widened by a
    // pixel (the picture must not depend on which band a face is tested
    // against).
    const auto misses = [&](int32_t lo, int32_t hi) {
      const int32_t margin = any ? 256 : 0;
      return hi + margin <= miss_below || lo - margin >= miss_above;
    };
    bool in_cache = true;
#pragma GCC unroll 4
    for (int k = 0; k < N; ++k) in_cache = in_cache && idx[k] < cached;
    if (in_cache) {
      // The common case, kept short: every face is visited once per
      // band, and most that get here miss it.
#pragma GCC unroll 4
      for (int k = 0; k < N; ++k) {
        const uint8_t oc = r.cache_outcode_[idx[k]];
        all &= oc;
        any |= oc;
      }
      if (all & kOutAll) return;
      if (!(any & kNoProjection)) {
        int32_t lo = cache[idx[0]].y, hi = lo;
#pragma GCC unroll 4
        for (int k = 1; k < N; ++k) {
          const int32_t y = cache[idx[k]].y;
          lo = y < lo ? y : lo;
          hi = y > hi ? y : hi;
        }
        if (misses(lo, hi)) return;
      }
#pragma GCC unroll 4
      for (int k = 0; k < N; ++k) cv[k] = cache[idx[k]];
    } else {
#pragma GCC unroll 4
      for (int k = 0; k < N; ++k) {
        const uint8_t oc = fetch(idx[k], &cv[k]);
        all &= oc;
        any |= oc;
      }
      if (all & kOutAll) return;
      if (!(any & kNoProjection)) {
        int32_t lo, hi;
        extent<N, &CachedVertex::y>(cv, &lo, &hi);
        if (misses(lo, hi)) return;
      }
    }
    // The clipper's scratch array is free once it has run, and the direct
    // path needs no clipping: one store serves both (a small stack).
    union Scratch {
      ClipVertex clip[kMaxPolyVerts];
      ScreenVertex screen[kMaxPolyVerts];
    } scratch;
    if (any == 0) {
      // Off screen sideways, facing and zero area first, as
      // prepare_polygon decides them (the same products): a rejected
      // face costs no vertex copies, no set-up and no set-up cache
      // slot. It counts as culled where prepare_polygon would count it.
      // (Faces in the triangle cache were tested once per frame.)
      if (!drawable<N>(m, cv)) {
        if (on_screen_x<N>(cv)) ++r.stats_.culled;  // then it faces away or has no area
        return;
      }
      ScreenVertex* sv = scratch.screen;
#pragma GCC unroll 4
      for (int k = 0; k < N; ++k) {
        sv[k].x = cv[k].x;
        sv[k].y = cv[k].y;
        sv[k].q = cv[k].q;
        attributes(m, idx[k], k, sv[k].a);
      }
      draw(band, mat, sv, N, g, false);
      return;
    }
    ++r.stats_.clipped;
    ClipVertex in[N], out[kMaxPolyVerts];
    for (int k = 0; k < N; ++k) {
      in[k] = camera_vertex(idx[k]);
      attributes(m, idx[k], k, in[k].a);
    }
    const int nc = clip_polygon(fc, static_cast<uint8_t>(any & kOutAll), in, N, out, scratch.clip, mat.num_attribs);
    if (nc < 3) {
      if (g < r.cfg_.triangle_cache) set_triangle_rows(g, 0, 0);  // nothing left in any band
      return;
    }
    ScreenVertex* sv = scratch.screen;
    bool ok = true;
    for (int k = 0; k < nc && ok; ++k) {
      const Vec3<Q16_16> p{Q16_16::from_raw(out[k].x), Q16_16::from_raw(out[k].y), Q16_16::from_raw(out[k].z)};
      ok = camera_project(*fc.cam, p, &sv[k].x, &sv[k].y);
      sv[k].q = depth_q(fc, out[k].z);
      for (int j = 0; j < kMaxAttribs; ++j) sv[k].a[j] = out[k].a[j];
    }
    if (ok) {
      draw(band, mat, sv, nc, g, true);
    } else if (g < r.cfg_.triangle_cache) {
      set_triangle_rows(g, 0, 0);
    }
  }
};

}  // namespace detail

Status texture_fill_apron(Texture& t, void* texels) {
  if (!texels || texels != t.texels || t.width < 1 || t.height < 1 || t.width > kTextureMaxSize ||
      t.height > kTextureMaxSize || t.stride < static_cast<uint32_t>(t.width) + 1) {
    return Status::invalid_argument;
  }
  const bool repeat = detail::texture_repeats(t);
  const uint32_t w = t.width, h = t.height, s = t.stride;
  auto fill = [&](auto* p) {
    for (uint32_t y = 0; y < h; ++y) p[y * s + w] = p[y * s + (repeat ? 0 : w - 1)];
    const uint32_t src = repeat ? 0 : h - 1;
    for (uint32_t x = 0; x <= w; ++x) p[h * s + x] = p[src * s + x];
  };
  if (t.format == TexFormat::rgb565) {
    fill(static_cast<uint16_t*>(texels));
  } else if (t.format == TexFormat::xrgb8888) {
    fill(static_cast<uint32_t*>(texels));
  } else {
    return Status::invalid_argument;
  }
  t.apron = true;
  return Status::ok;
}

size_t render_workspace_size(const RenderConfig& cfg) {
  if (check_config(cfg) != Status::ok) return 0;
  const size_t w = cfg.width, bh = cfg.band_height;
  size_t total = 0;
  if (!cfg.target) total += w * bh * static_cast<size_t>(bytes_per_pixel(cfg.format)) + kAlignSlack;
  total += w * bh * static_cast<size_t>(bytes_per_depth(cfg.depth)) + kAlignSlack;
  if (cfg.vertex_cache) total += size_t{cfg.vertex_cache} * (sizeof(detail::CachedVertex) + 1) + kAlignSlack;
  if (cfg.triangle_cache) total += size_t{cfg.triangle_cache} * 2 * sizeof(uint16_t) + kAlignSlack;
  if (cfg.setup_cache) {
    total += size_t{cfg.setup_cache} * setup_entry_bytes() + detail::prepared_polygon_align() - 1;
    total += size_t{cfg.setup_cache} * 2 * sizeof(uint32_t) + kAlignSlack;
    total += size_t{cfg.setup_cache} * 3 * sizeof(uint16_t) + 1;
  }
  return total;
}

Status Renderer::init(const RenderConfig& cfg, Arena& arena) {
  ready_ = false;
  const Status st = check_config(cfg);
  if (st != Status::ok) return st;
  const size_t w = cfg.width, bh = cfg.band_height;
  uint8_t* color = nullptr;
  uint32_t stride = 0;
  if (cfg.target) {
    color = cfg.target;
    stride = cfg.target_stride;
  } else {
    stride = static_cast<uint32_t>(w * static_cast<size_t>(bytes_per_pixel(cfg.format)));
    color = static_cast<uint8_t*>(arena.alloc(stride * bh, 4));
    if (!color) return Status::workspace_too_small;
  }
  void* depth = arena.alloc(w * bh * static_cast<size_t>(bytes_per_depth(cfg.depth)), 4);
  if (!depth) return Status::workspace_too_small;
  detail::CachedVertex* cache = nullptr;
  uint8_t* oc = nullptr;
  if (cfg.vertex_cache) {
    cache = arena.alloc_array<detail::CachedVertex>(cfg.vertex_cache);
    oc = arena.alloc_array<uint8_t>(cfg.vertex_cache);
    if (!cache || !oc) return Status::workspace_too_small;
  }
  uint16_t* tri = nullptr;
  if (cfg.triangle_cache) {
    tri = arena.alloc_array<uint16_t>(size_t{cfg.triangle_cache} * 2);
    if (!tri) return Status::workspace_too_small;
  }
  uint8_t* setups = nullptr;
  uint32_t* tags = nullptr;
  uint16_t* slots = nullptr;
  if (cfg.setup_cache) {
    setups = static_cast<uint8_t*>(arena.alloc(size_t{cfg.setup_cache} * setup_entry_bytes(), detail::prepared_polygon_align()));
    tags = arena.alloc_array<uint32_t>(size_t{cfg.setup_cache} * 2);
    slots = arena.alloc_array<uint16_t>(size_t{cfg.setup_cache} * 3);
    if (!setups || !tags || !slots) return Status::workspace_too_small;
  }
  cfg_ = cfg;
  setups_ = setups;
  setup_tags_ = tags;
  setup_tags2_ = tags ? tags + cfg.setup_cache : nullptr;
  setup_slots_ = slots;
  setup_slots2_ = slots ? slots + cfg.setup_cache : nullptr;
  setup_free_ = slots ? slots + 2 * size_t{cfg.setup_cache} : nullptr;
  setup_bytes_ = static_cast<uint32_t>(setup_entry_bytes());
  color_ = color;
  color_stride_ = stride;
  depth_ = depth;
  cache_ = cache;
  cache_outcode_ = oc;
  tri_bands_ = tri;
  stats_ = RenderStats{};
  ready_ = true;
  return Status::ok;
}

Status Renderer::render(const Camera& cam, const DrawList& list, uint32_t clear_color, BandSink sink, void* ctx) {
  if (!ready_) return Status::invalid_argument;
  if (!sink && !cfg_.target) return Status::invalid_argument;
  if (validate_camera(cam) != Status::ok) return Status::invalid_argument;
  const Status st = check_list(list);
  if (st != Status::ok) return st;

  stats_ = RenderStats{};
  for (uint32_t i = 0; i < list.num_meshes; ++i) stats_.triangles += list.meshes[i].num_triangles;

  detail::RenderFrame frame{*this, list, {&cam, cam.near_z.raw(), cam.far_z.raw(), kRenderGuardBandPx}};
  frame.fill_cache();
  if (cfg_.triangle_cache) frame.fill_triangle_bands();

  const int32_t height = cfg_.height;
  for (int32_t y0 = 0; y0 < height; y0 += cfg_.band_height) {
    const int32_t y1 = y0 + cfg_.band_height < height ? y0 + cfg_.band_height : height;
    detail::BandTarget band{};
    band.y0 = y0;
    band.y1 = y1;
    band.width = cfg_.width;
    band.height = cfg_.height;
    band.color = cfg_.target ? color_ + static_cast<size_t>(y0) * color_stride_ : color_;
    band.color_stride = color_stride_;
    band.depth = depth_;
    band.format = cfg_.format;
    band.depth_format = cfg_.depth;
    clear_band(band, clear_color);
    const uint16_t band_index = static_cast<uint16_t>(y0 / cfg_.band_height);
    uint32_t first_tri = 0;
    for (uint32_t i = 0; i < list.num_meshes; ++i) {
      frame.draw_mesh(band, list.meshes[i], first_tri, band_index);
      const uint32_t nt = list.meshes[i].num_triangles;
      first_tri = nt > UINT32_MAX - first_tri ? UINT32_MAX : first_tri + nt;
    }
    if (frame.live | frame.fresh) frame.end_band(y1);
    if (sink) {
      const Band out{band.color, color_stride_, static_cast<uint16_t>(y0), static_cast<uint16_t>(y1 - y0),
                     cfg_.width, cfg_.format};
      if (!sink(ctx, out)) return Status::aborted;
    }
  }
  return Status::ok;
}

}  // namespace vds
