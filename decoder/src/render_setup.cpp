// Polygon set-up of the renderer: everything about a polygon that does not
// depend on the band, by stage: the rows it covers and its outline, the
// fan triangle the planes are fitted to, the divisor and numerators at its
// vertices for its shading (colour, texture coordinates or the rows of a
// view homography), the exponents that keep them in range, and the planes
// the span loops (render_span.cpp) evaluate. docs/renderer.md has the
// fixed-point scaling.
#include "render_span.h"
#include "vds/render_raster.h"

namespace vds::detail {

namespace {


// 1/den ~= mant * 2^-shift for den > 0, 31 significant bits.
struct Inv {
  uint32_t mant;
  int shift;
};
Inv inverse(uint64_t den) {
  const int nb = bitlen64(den);
  const uint32_t m = nb > 32 ? static_cast<uint32_t>(den >> (nb - 32)) : static_cast<uint32_t>(den << (32 - nb));
  // recip_mant(m) = floor(2^63 / m) and den ~= m 2^(nb - 32).
  return {recip_mant(m), 31 + nb};
}

// num * 2^extra / den (den from inverse()), saturated to +-kGradLimit.
int64_t mul_inv(int64_t num, Inv inv, int extra) {
  if (num == 0) return 0;
  const bool neg = num < 0;
  uint64_t u = abs64(num);
  int sn = bitlen64(u) - 31;
  if (sn < 0) sn = 0;
  u >>= sn;
  const uint64_t p = u * inv.mant;  // < 2^63
  const int e = sn + extra - inv.shift;
  uint64_t r;
  if (e >= 0) {
    if (e >= 47 || p >= (static_cast<uint64_t>(kGradLimit) >> e)) {
      r = static_cast<uint64_t>(kGradLimit);
    } else {
      r = p << e;
    }
  } else {
    r = (-e >= 64) ? 0 : ((p >> (-e - 1)) + 1) >> 1;  // rounded
    if (r > static_cast<uint64_t>(kGradLimit)) r = static_cast<uint64_t>(kGradLimit);
  }
  return neg ? -static_cast<int64_t>(r) : static_cast<int64_t>(r);
}

// The plane through three vertices (Q24.8 positions) with values A (|A| <=
// 2^31): dA/dx = (dA1 dy2 - dA2 dy1) / area2, dA/dy = (dx1 dA2 - dx2 dA1) / area2
// per 1/256 pixel, times 2^8 per pixel, times 2^16 for Q.16.
Plane plane_from(const ScreenVertex& a, const ScreenVertex& b, const ScreenVertex& c, const int64_t val[3],
                 Inv inv, bool negative_area, int32_t xr, int32_t yr) {
  const int64_t da1 = val[1] - val[0], da2 = val[2] - val[0];  // < 2^32
  const int64_t dx1 = int64_t{b.x} - a.x, dy1 = int64_t{b.y} - a.y;
  const int64_t dx2 = int64_t{c.x} - a.x, dy2 = int64_t{c.y} - a.y;  // < 2^22
  const int64_t nx = da1 * dy2 - da2 * dy1;                            // < 2^55
  const int64_t ny = dx1 * da2 - dx2 * da1;
  Plane p;
  p.gx = mul_inv(nx, inv, 24);
  p.gy = mul_inv(ny, inv, 24);
  if (negative_area) {
    p.gx = -p.gx;
    p.gy = -p.gy;
  }
  // Value at the centre of pixel (xr, yr), offsets in 1/256 pixel.
  const int64_t ox = int64_t{xr} * 256 + 128 - a.x;
  const int64_t oy = int64_t{yr} * 256 + 128 - a.y;
  p.a0 = wrap_add64(val[0] * (int64_t{1} << kPlaneFrac), shift_floor(wrap_add64(wrap_mul64(p.gx, ox), wrap_mul64(p.gy, oy)), 8));
  return p;
}

// The plane of c0 x + c1 y + c2 at pixel centres (x + 1/2, y + 1/2), |c| < 2^31.
Plane plane_linear(int64_t c0, int64_t c1, int64_t c2, int32_t xr, int32_t yr) {
  Plane p;
  p.gx = c0 * (int64_t{1} << kPlaneFrac);
  p.gy = c1 * (int64_t{1} << kPlaneFrac);
  // (c0 (2 xr + 1) + c1 (2 yr + 1) + 2 c2) 2^15: below 3 * 2^31 * 2^15 * 2^15.
  p.a0 = (c0 * (2 * int64_t{xr} + 1) + c1 * (2 * int64_t{yr} + 1) + 2 * c2) * (int64_t{1} << (kPlaneFrac - 1));
  return p;
}


int64_t floor_div(int64_t a, int64_t b) {  // b > 0
  int64_t q = a / b;
  if (q * b > a) --q;
  return q;
}
int32_t floor_div32(int32_t a, int32_t b) {  // b > 0; a hardware division on Cortex-M4
  int32_t q = a / b;
  if (q * b > a) --q;
  return q;
}

}  // namespace

// A polygon set up for rasterisation: everything draw_polygon computes that
// does not depend on the band, so that one set-up serves every band the
// polygon crosses (RenderConfig::setup_cache).
struct PreparedPolygon {
  PolySetup s;
  SpanFn fn;                        // nullptr: nothing to draw (culled, off screen, compiled out)
  int16_t row_begin, row_end;       // rows [row_begin, row_end) the polygon can cover (|row| <= 2^13: kRasterCoordLimit)
  uint8_t n;                        // outline vertices
  bool culled;                      // facing or zero area (counted per band it touches)
  bool set_up;                      // planes computed (counted per band it touches)
  bool whole;                       // rasterised as one convex polygon (a face of more than 3 corners), else as a fan
  RasterVertex outline[kMaxPolyVerts];
};

size_t prepared_polygon_bytes() { return sizeof(PreparedPolygon); }
size_t prepared_polygon_align() { return alignof(PreparedPolygon); }

namespace {

// --- Stage 1: where the polygon lies ---------------------------------------
// Rows and columns the polygon can touch (pixel centres inside its box) and
// its outline. false: nothing of it is on the target.
// *x_min and *x_max: the outline's extremes (Q24.8), for fast_safe.
bool place(const PolygonTarget& target, const ScreenVertex* v, int n, PreparedPolygon* pp, int32_t* x_min, int32_t* x_max) {
  int32_t xmin = v[0].x, xmax = v[0].x, ymin = v[0].y, ymax = v[0].y;
  for (int i = 1; i < n; ++i) {
    xmin = v[i].x < xmin ? v[i].x : xmin;
    xmax = v[i].x > xmax ? v[i].x : xmax;
    ymin = v[i].y < ymin ? v[i].y : ymin;
    ymax = v[i].y > ymax ? v[i].y : ymax;
  }
  *x_min = xmin;
  *x_max = xmax;
  if (xmin < -kRasterCoordLimit || xmax > kRasterCoordLimit || ymin < -kRasterCoordLimit || ymax > kRasterCoordLimit) {
    pp->row_begin = pp->row_end = 0;
    return false;  // cannot happen after guard-band clipping; kept as a hard limit
  }
  pp->row_begin = static_cast<int16_t>(raster_row(ymin));
  pp->row_end = static_cast<int16_t>(raster_row(ymax));
  if (raster_row(xmax) <= 0 || raster_row(xmin) >= target.width) return false;
  for (int i = 0; i < n; ++i) pp->outline[i] = {v[i].x, v[i].y};
  return true;
}

// --- Stage 2: orientation and the fan triangle the planes are fitted to ----
struct Fan {
  int64_t area;  // twice the signed area of the polygon
  int64_t best;  // twice the signed area of the best-conditioned fan triangle
  int bi;        // that triangle is v[0], v[bi], v[bi + 1]
};

Fan fan_triangle(const ScreenVertex* v, int n) {
  Fan f{0, 0, 1};
  for (int i = 1; i + 1 < n; ++i) {
    const int64_t a = int64_t{v[i].x - v[0].x} * (v[i + 1].y - v[0].y) - int64_t{v[i + 1].x - v[0].x} * (v[i].y - v[0].y);
    f.area += a;
    if (abs64(a) > abs64(f.best)) {
      f.best = a;
      f.bi = i;
    }
  }
  return f;
}

// --- Stage 3: the divisor and numerators at the vertices ---------------------
// The divisor W and the numerators N at every vertex of the polygon, in
// their natural scale, give the exponents kw and kn of the planes: N / 2^kn
// below 2^30, W / 2^kw below 2^30, and, when one set of exponents serves
// the whole polygon (the fast span set-up, checked per span anyway), kn
// raised until sh = 30 - (g + kn - kw) - clz(W) stays in [0, 31].
// Extremes over the vertices, and N at the three vertices of the plane fit
// (kept instead of all vertices' values: this runs on a small stack).
struct VertexValues {
  int ref[3];  // the vertices of the plane fit (distinct)
  int64_t wmin = INT64_MAX, wmax = INT64_MIN;
  uint64_t nmax = 0;
  int64_t nref[3][3];
  int g = 0;  // result = N / W * 2^(g + kn - kw)
  int kn = 0, kw = 0;
  // The view homography's rows (view_mapped only), already scaled by 2^kn
  // (numerators) and 2^kw (divisor).
  int64_t wrow[3], nrow[2][3];

  __attribute__((always_inline)) void note(int i, int64_t w, const int64_t* nvals, int count) {
    wmin = w < wmin ? w : wmin;
    wmax = w > wmax ? w : wmax;
    const int k = i == ref[0] ? 0 : (i == ref[1] ? 1 : (i == ref[2] ? 2 : -1));
    for (int j = 0; j < count; ++j) {
      const uint64_t mag = abs64(nvals[j]);
      nmax = mag > nmax ? mag : nmax;
      if (k >= 0) nref[j][k] = nvals[j];
    }
  }
};

// Gouraud: N = colour (Q8.8) q < 2^46; the result is the colour in Q8.8.
void gouraud_values(const ScreenVertex* v, int n, VertexValues& vv) {
  for (int i = 0; i < n; ++i) {
    const int64_t nvals[3] = {int64_t{v[i].a[0]} * v[i].q, int64_t{v[i].a[1]} * v[i].q, int64_t{v[i].a[2]} * v[i].q};
    vv.note(i, v[i].q, nvals, 3);
  }
}

// Affine-in-1/z texture coordinates: N = (u - origin) q.
void texture_values(const Texture& t, bool repeat, int f, const ScreenVertex* v, int n, VertexValues& vv) {
  // Texture origin: a whole number of texture periods below the polygon
  // keeps the numerators small (repeat only; clamp needs true coordinates).
  int64_t org[2] = {0, 0};
  if (repeat) {
    const int32_t size[2] = {t.width, t.height};
    for (int j = 0; j < 2; ++j) {
      int32_t mn = v[0].a[j];
      for (int i = 1; i < n; ++i) mn = v[i].a[j] < mn ? v[i].a[j] : mn;
      org[j] = int64_t{floor_div32(mn >> 16, size[j])} * size[j] * 65536;
    }
  }
  const int64_t half = f ? 32768 : 0;  // bilinear blends around u - 1/2
  for (int i = 0; i < n; ++i) {
    const int64_t nvals[2] = {(int64_t{v[i].a[0]} - org[0] - half) * v[i].q,  // < 2^33 * 2^30
                              (int64_t{v[i].a[1]} - org[1] - half) * v[i].q};
    vv.note(i, v[i].q, nvals, 2);
  }
  vv.g = f - 16;  // u (Q16.16) = N / q, wanted in Q.f
}

// Mesh colors: the corners' barycentric weights (Q16.16) scaled to the
// face's lattice, N = (R a + 1/2 for nearest sampling) q.
void lattice_values(int res_log2, int f, const ScreenVertex* v, int n, VertexValues& vv) {
  const int64_t half = f ? 0 : 32768;  // nearest: the lattice point nearest, by rounding
  for (int i = 0; i < n; ++i) {
    const int64_t nvals[2] = {((int64_t{v[i].a[0]} << res_log2) + half) * v[i].q,  // < 2^27 * 2^30
                              ((int64_t{v[i].a[1]} << res_log2) + half) * v[i].q};
    vv.note(i, v[i].q, nvals, 2);
  }
  vv.g = f - 16;
}

// View-mapped: the rows of the homography (vds/homography.h), which works on
// coordinates / 256: per pixel, 256 W = h20 x + h21 y + 256 h22 and 65536 S =
// 256 (h00 x + h01 y) + 65536 h02, so that texel u = 65536 S / (256 W).
void view_mapped_values(const Texture& t, const Homography& map, bool repeat, int f, const ScreenVertex* v, int n,
                        VertexValues& vv) {
  const int32_t(&h)[3][3] = map.m;
  const ScreenVertex& a = v[0];
  int64_t* wrow = vv.wrow;
  wrow[0] = h[2][0];
  wrow[1] = h[2][1];
  wrow[2] = int64_t{h[2][2]} * 256;
  int64_t srow[2][3];
  for (int j = 0; j < 2; ++j) {
    srow[j][0] = int64_t{h[j][0]} * 256;
    srow[j][1] = int64_t{h[j][1]} * 256;
    srow[j][2] = int64_t{h[j][2]} * 65536;
  }
  int64_t org[2] = {0, 0};
  if (repeat) {
    // Origin from the first vertex: u = 65536 S / (256 W) there; both rows
    // evaluated in Q.8 (below 2^62).
    const int64_t W = wrow[0] * a.x + wrow[1] * a.y + wrow[2] * 256;
    const int32_t size[2] = {t.width, t.height};
    for (int j = 0; j < 2 && W > 0; ++j) {
      const int64_t X = wrap_add64(wrap_add64(wrap_mul64(srow[j][0], a.x), wrap_mul64(srow[j][1], a.y)), wrap_mul64(srow[j][2], 256));
      int64_t u = floor_div(X, W);
      u = u < -(int64_t{1} << 20) ? -(int64_t{1} << 20) : (u > (int64_t{1} << 20) ? (int64_t{1} << 20) : u);
      org[j] = floor_div(u, size[j]) * size[j];
    }
  }
  // Nearest: S - o W. Bilinear: 2 S - (2 o + 1) W, i.e. 2 (u - o - 1/2) W.
  int64_t(&nrow)[2][3] = vv.nrow;
  uint64_t mx = 0;
  for (int j = 0; j < 2; ++j)
    for (int k = 0; k < 3; ++k) {
      nrow[j][k] = f ? 2 * srow[j][k] - (2 * org[j] + 1) * wrow[k] : srow[j][k] - org[j] * wrow[k];
      mx = abs64(nrow[j][k]) > mx ? abs64(nrow[j][k]) : mx;
    }
  // Rows brought below 2^30 first (plane_linear's range); then the values
  // at the vertices, (c0 X + c1 Y) / 256 + c2 with X, Y in Q24.8.
  const int r0 = bitlen64(mx) - 30 > 0 ? bitlen64(mx) - 30 : 0;
  uint64_t wmx = 0;
  for (int k = 0; k < 3; ++k) wmx = abs64(wrow[k]) > wmx ? abs64(wrow[k]) : wmx;
  const int w0 = bitlen64(wmx) - 30 > 0 ? bitlen64(wmx) - 30 : 0;
  for (int k = 0; k < 3; ++k) {
    wrow[k] = shift_round(wrow[k], w0);
    for (int j = 0; j < 2; ++j) nrow[j][k] = shift_round(nrow[j][k], r0);
  }
  for (int i = 0; i < n; ++i) {
    const int64_t nvals[2] = {((nrow[0][0] * v[i].x + nrow[0][1] * v[i].y) >> 8) + nrow[0][2],
                              ((nrow[1][0] * v[i].x + nrow[1][1] * v[i].y) >> 8) + nrow[1][2]};
    vv.note(i, ((wrow[0] * v[i].x + wrow[1] * v[i].y) >> 8) + wrow[2], nvals, 2);
  }
  vv.kw = w0;
  vv.kn = r0;
  vv.g = f ? f - 1 : f;
}

// --- Stage 4: exponents and planes ------------------------------------------
// The exponents of the numerators and the divisor, the fast span set-up
// when one set serves the whole polygon, and the planes at those exponents.
void fit_planes(PolySetup& s, VertexValues& vv, const ScreenVertex* v, const Fan& fan, Inv inv) {
  const ScreenVertex& a = v[0];
  const ScreenVertex& b = v[fan.bi];
  const ScreenVertex& c = v[fan.bi + 1];
  const bool neg = fan.best < 0;
  int kn = vv.kn, kw = vv.kw;
  // Divisor: proj scales W below 2^30 (q already is).
  int kw_extra = 0;
  if (s.proj && vv.wmax > 0)
    kw_extra = bitlen64(static_cast<uint64_t>(vv.wmax)) - 30 > 0 ? bitlen64(static_cast<uint64_t>(vv.wmax)) - 30 : 0;
  int kn_min = bitlen64(vv.nmax) - 30;  // smallest kn that keeps every |N| below 2^30
  if (s.proj) {
    // The rows are shifted further: below 2^30 already, never scaled up.
    kn_min = kn_min > 0 ? kn_min : 0;
  } else if (kn_min < -16) {
    kn_min = -16;
  }
  const int kn_base = kn;  // proj: shift already applied to the rows
  kn = kn_base + kn_min;
  kw += kw_extra;
  // The fast window, with the divisor range widened by 1/64 for the
  // rounding of the planes between the vertices.
  const int64_t wlo_v = shift_floor(vv.wmin, kw_extra), whi_v = shift_floor(vv.wmax, kw_extra);
  const int64_t wl = wlo_v - (wlo_v >> 6), wh = whi_v + (whi_v >> 6);
  if (wl >= 1 && wh <= kI32Max) {
    const int z_lo = clz32(static_cast<uint32_t>(wh));
    const int z_hi = clz32(static_cast<uint32_t>(wl));
    int bw = vv.g + kn - kw;
    const int raise = -1 - z_lo - bw;  // sh <= 31 at the largest W
    if (raise > 0) {
      kn += raise;
      bw += raise;
    }
    if (30 - z_hi - bw >= 0) {  // sh >= 0 at the smallest W
      s.fast = true;
      s.fast_shb = 30 - bw;
      const int zmax = s.fast_shb < 31 ? s.fast_shb : 31;
      const int zmin = s.fast_shb - 31 > 0 ? s.fast_shb - 31 : 0;
      s.wlo = static_cast<int32_t>(uint32_t{1} << (31 - zmax));
      s.whi = zmin == 0 ? INT32_MAX : static_cast<int32_t>((uint32_t{1} << (32 - zmin)) - 1);
    }
  }
  // The planes at the chosen exponents.
  if (s.proj) {
    const int en = kn - kn_base, ew = kw_extra;
    for (int j = 0; j < 2; ++j) {
      s.n[j] = plane_linear(shift_round(vv.nrow[j][0], en), shift_round(vv.nrow[j][1], en),
                            shift_round(vv.nrow[j][2], en), s.xr, s.yr);
    }
    s.w = plane_linear(shift_round(vv.wrow[0], ew), shift_round(vv.wrow[1], ew), shift_round(vv.wrow[2], ew), s.xr, s.yr);
    s.fast_dw = step16(s.w.gx);
  } else {
    s.fast_dw = s.fast_dq;
    for (int j = 0; j < s.nn; ++j) {
      const int64_t val[3] = {shift_round(vv.nref[j][0], kn), shift_round(vv.nref[j][1], kn), shift_round(vv.nref[j][2], kn)};
      s.n[j] = plane_from(a, b, c, val, inv, neg, s.xr, s.yr);
    }
  }
  for (int j = 0; j < s.nn; ++j) s.fast_dn[j] = step16(s.n[j].gx);
  s.b0 = vv.g + kn - kw;
}

// A plane in row units (PolySetup::fast_c*, fast_g*): its value at pixel
// (dx, dy) from its reference pixel and its y step, each rounded; false when
// either or the x step leaves int32 (the span start values then take the
// planes).
bool row_unit(const Plane& p, int32_t dx, int32_t dy, int32_t step, int32_t* c, int32_t* g) {
  const int64_t half = int64_t{1} << (kPlaneFrac - 1);
  const int64_t cv = wrap_add64(eval(p, dx, dy), half) >> kPlaneFrac;
  const int64_t gv = wrap_add64(p.gy, half) >> kPlaneFrac;
  if (cv < kI32Min || cv > kI32Max || gv < kI32Min || gv > kI32Max) return false;
  if (step == INT32_MIN || step == INT32_MAX) return false;  // step16 saturated
  *c = static_cast<int32_t>(cv);
  *g = static_cast<int32_t>(gv);
  return true;
}
bool fast_rows(const PolygonTarget& t, PolySetup& s) {
  s.fast_xr = s.xr < 0 ? 0 : (s.xr >= t.width ? t.width - 1 : s.xr);
  s.fast_yr = s.yr < 0 ? 0 : (s.yr >= t.height ? t.height - 1 : s.yr);
  const int32_t dx = s.fast_xr - s.xr, dy = s.fast_yr - s.yr;
  if (!row_unit(s.q, dx, dy, s.fast_dq, &s.fast_cq, &s.fast_gq)) return false;
  if (s.proj && !row_unit(s.w, dx, dy, s.fast_dw, &s.fast_cw, &s.fast_gw)) return false;
  for (int j = 0; j < s.nn; ++j)
    if (!row_unit(s.n[j], dx, dy, s.fast_dn[j], &s.fast_cn[j], &s.fast_gn[j])) return false;
  return true;
}

// Whether a fast plane, c + step dx + g dy at pixel (xr + dx, yr + dy),
// lies inside [lo, hi] at every pixel of a box (dx in [dx0, dx1], dy in
// [dy0, dy1]): it is affine, so its extremes over the box lie at corners.
// Each product is below 2^31 2^12 (the box lies on the frame).
struct FastBox {
  int32_t dx0, dx1, dy0, dy1;
};
bool fast_bounded(int32_t c, int32_t step, int32_t g, int64_t lo, int64_t hi, const FastBox& b) {
  const int64_t x0 = int64_t{step} * b.dx0, x1 = int64_t{step} * b.dx1;
  const int64_t y0 = int64_t{g} * b.dy0, y1 = int64_t{g} * b.dy1;
  const int64_t low = c + (x0 < x1 ? x0 : x1) + (y0 < y1 ? y0 : y1);
  const int64_t high = c + (x0 < x1 ? x1 : x0) + (y0 < y1 ? y1 : y0);
  return low >= lo && high <= hi;
}
// Whether every fast start value of every pixel the polygon covers lies
// inside the limits row_fast checks (PolySetup::fast_safe). The pixels
// covered lie in the box of the outline's columns and rows on the frame (a
// pixel is covered when its centre is inside): x in [xmin, xmax] (Q24.8).
bool fast_safe(const PolygonTarget& t, const PolySetup& s, int32_t xmin, int32_t xmax, int32_t row_begin, int32_t row_end) {
  const int32_t c0 = raster_row(xmin) > 0 ? raster_row(xmin) : 0;
  const int32_t c1 = raster_row(xmax) < t.width - 1 ? raster_row(xmax) : t.width - 1;
  const int32_t r0 = row_begin > 0 ? row_begin : 0;
  const int32_t r1 = row_end < t.height - 1 ? row_end : t.height - 1;
  if (c0 > c1 || r0 > r1) return false;
  const FastBox b{c0 - s.fast_xr, c1 - s.fast_xr, r0 - s.fast_yr, r1 - s.fast_yr};
  const bool q_is_w = s.nn > 0 && !s.proj;
  if (!fast_bounded(s.fast_cq, s.fast_dq, s.fast_gq, q_is_w ? s.fast_qlo : 1, q_is_w ? s.fast_qhi : kQMax, b))
    return false;
  if (s.nn > 0 && s.proj && !fast_bounded(s.fast_cw, s.fast_dw, s.fast_gw, s.wlo, s.whi, b)) return false;
  for (int j = 0; j < s.nn; ++j)
    if (!fast_bounded(s.fast_cn[j], s.fast_dn[j], s.fast_gn[j], -kNumLimit, kNumLimit, b)) return false;
  return true;
}

// Whether a view a ViewMapSource gives has the form of the mesh's texture,
// which render() validated and the span function was chosen for.
bool same_form(const Texture& a, const Texture& b) {
  return a.format == b.format && a.address == b.address && a.apron == b.apron && a.width == b.width &&
         a.height == b.height && a.stride == b.stride && a.chroma_stride == b.chroma_stride &&
         a.texels != nullptr && (a.format != TexFormat::ycbcr420 || (a.cb != nullptr && a.cr != nullptr));
}

// Whether a face is drawn in one colour, its texture's at one point (a
// textured face's centre, a view-mapped face's ViewMapSource::point): its
// outline spans at most RenderConfig::point_face_span pixel columns and rows.
bool point_face(const MaterialCtx& mat, const PreparedPolygon& pp, int32_t xmin, int32_t xmax) {
  const Mesh& m = *mat.mesh;
  return mat.point_span > 0 && pp.row_end - pp.row_begin <= mat.point_span &&
         raster_row(xmax) - raster_row(xmin) <= mat.point_span &&
         (m.shading == Shading::texture || (m.shading == Shading::view_mapped && m.views != nullptr && m.views->point != nullptr)) &&
         point_samples(*m.texture);
}
// That point, a Q24.8 texel position: a view-mapped face's from its
// source (false: not given), a textured face's the mean of its corners'
// texture coordinates (Q16.16 texels).
bool face_point(const MaterialCtx& mat, const ScreenVertex* v, int n, const Texture** tex, int32_t* u_q8, int32_t* v_q8) {
  const Mesh& m = *mat.mesh;
  if (m.shading == Shading::view_mapped) return m.views->point(m.views->ctx, mat.tri, mat.first, tex, u_q8, v_q8);
  int64_t su = 0, sv = 0;
  for (int i = 0; i < n; ++i) su += v[i].a[0], sv += v[i].a[1];
  *tex = m.texture;
  *u_q8 = static_cast<int32_t>((su / n) >> 8);
  *v_q8 = static_cast<int32_t>((sv / n) >> 8);
  return true;
}

}  // namespace

void prepare_polygon(const PolygonTarget& target, const MaterialCtx& mat, const ScreenVertex* v, int n, PreparedPolygon* pp) {
  pp->fn = nullptr;
  pp->culled = false;
  pp->set_up = false;
  pp->whole = mat.corners > 3;
  pp->n = static_cast<uint8_t>(n);
  int32_t xmin, xmax;
  if (!place(target, v, n, pp, &xmin, &xmax)) return;
  const Fan fan = fan_triangle(v, n);
  const Mesh& m = *mat.mesh;
  if (fan.area == 0 || fan.best == 0 || (m.cull == Cull::back && fan.area > 0) || (m.cull == Cull::front && fan.area < 0)) {
    pp->culled = true;
    return;
  }
  pp->set_up = true;

  const ScreenVertex& a = v[0];
  const Inv inv = inverse(abs64(fan.best));
  // Every field the span functions read is set below (no zeroing of the
  // whole struct: it is a few hundred bytes and this runs per triangle).
  PolySetup& s = pp->s;
  s.xr = a.x >> 8;
  s.yr = a.y >> 8;
  s.nn = 0;
  s.proj = false;
  s.b0 = 0;
  s.flat = 0;
  s.fast = false;
  s.wlo = 1;
  s.whi = kQMax;
  {
    const int64_t qv[3] = {a.q, v[fan.bi].q, v[fan.bi + 1].q};
    s.q = plane_from(a, v[fan.bi], v[fan.bi + 1], qv, inv, fan.best < 0, s.xr, s.yr);
  }
  s.fast_dq = step16(s.q.gx);
  bool repeat = false;
  // The homography rows and nref are set before any use: no zeroing, which
  // costs a memset call per polygon.
  const Texture* point_tex = nullptr;
  int32_t point_u = 0, point_v = 0;
  VertexValues vv;
  vv.ref[0] = 0;
  vv.ref[1] = fan.bi;
  vv.ref[2] = fan.bi + 1;
  if (m.shading == Shading::flat) {
    s.flat = target.format == PixelFormat::rgb565 ? pack565(m.color) : (m.color & 0xFFFFFFu);
  } else if (m.shading == Shading::gouraud) {
    s.nn = 3;
    gouraud_values(v, n, vv);
  } else if (m.shading == Shading::mesh_colors) {
    const MeshColorsSurface& sf = *m.surface;
    if (!sf.face(sf.ctx, mat.tri, &s.lat.face) || !lattice_face_valid(s.lat.face, sf.samples)) return;
    s.lat.y = sf.y;
    s.lat.cb = sf.cb;
    s.lat.cr = sf.cr;
    s.lat.res = int32_t{1} << s.lat.face.res_log2;
    s.nn = 2;
    lattice_values(s.lat.face.res_log2, m.filter == Filter::nearest ? 0 : kLatticeFracBits, v, n, vv);
  } else if (point_face(mat, *pp, xmin, xmax) && face_point(mat, v, n, &point_tex, &point_u, &point_v)) {
    // A small face in one colour: its texture's sample at the point.
    if (point_tex == nullptr || !same_form(*point_tex, *m.texture)) return;
    s.flat = point_colour(target, m, *point_tex, point_u, point_v);
  } else {
    point_tex = nullptr;
    const Texture* tex = m.texture;
    const Homography* map = &m.view_map;
    Homography asked;
    if (m.shading == Shading::view_mapped && m.views != nullptr) {
      map = &asked;
      if (!m.views->map(m.views->ctx, mat.tri, mat.first, &tex, &asked) || !same_form(*tex, *m.texture)) return;
    }
    repeat = texture_repeats(*tex);
    s.tex = make_tex_ctx(*tex, repeat);
    s.nn = 2;
    const int f = fraction_bits(m, target.format);
    if (m.shading == Shading::texture) {
      texture_values(*tex, repeat, f, v, n, vv);
    } else {  // view_mapped
      s.proj = true;
      view_mapped_values(*tex, *map, repeat, f, v, n, vv);
    }
  }
  if (s.nn)
    fit_planes(s, vv, v, fan, inv);
  else
    s.fast = true;  // flat: q only

  if (s.fast && !fast_rows(target, s)) s.fast = false;
  s.fast_qlo = s.wlo > 1 ? s.wlo : 1;
  s.fast_qhi = s.whi < kQMax ? s.whi : kQMax;
  // Empty: no span of a non-projective polygon passes both checks anyway.
  if (s.nn && !s.proj && s.fast_qlo > s.fast_qhi) s.fast = false;
  // (View-mapped polygons only: on the other materials' larger polygons the
  // check at set-up cost more than the spans saved, bench/results/render.md.)
  s.fast_safe = s.fast && s.proj && fast_safe(target, s, xmin, xmax, pp->row_begin, pp->row_end);
  pp->fn = point_tex != nullptr ? select_flat_span(target) : select_span(target, m, repeat);
}

int32_t prepared_row_end(const PreparedPolygon& pp) { return pp.row_end; }

void draw_prepared(const BandTarget& band, const PreparedPolygon& pp, RenderStats& stats) {
  if (pp.row_end <= band.y0 || pp.row_begin >= band.y1) return;
  if (pp.culled) ++stats.culled;
  const SpanFn fn = pp.fn;
  if (!fn) return;
  const PolySetup& s = pp.s;
  const RasterVertex* o = pp.outline;
  const auto span = [&](int32_t y, int32_t xa, int32_t xb) {
    fn(band, s, y, xa, xb);
    ++stats.spans;
    stats.pixels += static_cast<uint32_t>(xb - xa);
  };
  if (pp.whole) {
    raster_convex(o, pp.n, band.y0, band.y1, band.width, span);
    return;
  }
  for (int i = 1; i + 1 < pp.n; ++i) {
    const RasterVertex rv[3] = {o[0], o[i], o[i + 1]};
    raster_triangle(rv, band.y0, band.y1, band.width, span);
  }
}

void draw_polygon(const BandTarget& band, const MaterialCtx& mat, const ScreenVertex* v, int n, RenderStats& stats) {
  PreparedPolygon pp;
  prepare_polygon(PolygonTarget{band.width, band.height, band.format, band.depth_format}, mat, v, n, &pp);
  if (pp.set_up && pp.row_end > band.y0 && pp.row_begin < band.y1) ++stats.setups;
  draw_prepared(band, pp, stats);
}

}  // namespace vds::detail

