// vds client library: the exact scanline edge walker of the renderer (the
// top-left fill rule of vds/render.h on Q24.8 vertices). Public so that tests
// and tools can enumerate the very spans the renderer fills.
//
// A pixel (x, y) is covered iff its centre (x + 1/2, y + 1/2) satisfies
//   y_top <= yc < y_bottom                 (rows: top edge in, bottom edge out)
//   x_left(yc) <= xc < x_right(yc)         (left edge in, right edge out)
// so the first pixel of a span is ceil(x_left - 1/2) and the end (exclusive)
// is ceil(x_right - 1/2), the same function for both sides. Each edge is
// walked from its upper end to its lower end whatever triangle it belongs to,
// with an exact incremental division (a Bresenham-style remainder), so two
// triangles sharing an edge compute bit-identical crossings.
#pragma once
#include <cstdint>

namespace vds {

struct RasterVertex {
  int32_t x, y;  // Q24.8 pixels
};

// |x| and |y| of every vertex must not exceed this (8192 pixels): it keeps
// the walker's denominators below 2^30. The renderer's guard band stays inside.
constexpr int32_t kRasterCoordLimit = int32_t{1} << 21;

// The first row whose centre is at or below y (Q24.8): ceil((y - 128) / 256).
constexpr int32_t raster_row(int32_t y_q8) { return (y_q8 + 127) >> 8; }

// One edge from (x0, y0) to (x1, y1), y1 > y0, positioned at a row: x is
// ceil((x_edge(yc) - 128) / 256) in pixels, with x_edge the exact crossing.
//   N(row) = (x0 - 128) dy + (256 row + 128 - y0) dx,  D = 256 dy,  x = ceil(N / D)
//   N = x D - rem with 0 <= rem < D; a row step adds 256 dx = step D + frac.
struct RasterEdge {
  int32_t x;
  int32_t rem;
  int32_t step;
  int32_t frac;
  int32_t den;

  void init(RasterVertex top, RasterVertex bottom, int32_t row) {
    const int32_t dy = bottom.y - top.y;  // > 0, <= 2^22
    const int32_t dx = bottom.x - top.x;  // |dx| <= 2^22
    den = dy << 8;                        // <= 2^30
    const int64_t n = int64_t{top.x - 128} * dy + (int64_t{row} * 256 + 128 - top.y) * dx;
    // ceil(n / den) without a 64-bit division (a library call on Cortex-M):
    // the quotient is a pixel column (|x| < 2^15 for rows inside the edge),
    // so n and den scaled down together keep den above 2^13 and a 32-bit
    // division lands within a few units; the exact remainder fixes it up.
    const uint64_t an = n < 0 ? 0 - static_cast<uint64_t>(n) : static_cast<uint64_t>(n);
    const int bits = 64 - __builtin_clzll(an | 1);
    const int s = bits > 31 ? bits - 31 : 0;
    int32_t q = static_cast<int32_t>(n >> s) / ((den >> s) | 1);
    int64_t r = int64_t{q} * den - n;  // want 0 <= r < den
    while (r < 0) {
      ++q;
      r += den;
    }
    while (r >= den) {
      --q;
      r -= den;
    }
    x = q;
    rem = static_cast<int32_t>(r);
    int32_t st = dx / dy;
    if (st * dy > dx) --st;  // floor
    step = st;
    frac = (dx - st * dy) << 8;  // [0, den)
  }

  void advance() {
    // N' = (x + step) D + (frac - rem).
    x += step;
    if (frac > rem) {
      ++x;
      rem += den - frac;
    } else {
      rem -= frac;
    }
  }
};

// Calls fn(y, x_begin, x_end) for each non-empty span of the triangle
// v[0..2] (any order, any orientation) in rows [y_begin, y_end), limited to
// x in [0, x_limit). Vertices must satisfy kRasterCoordLimit; a triangle of
// zero area produces no span. Returns the number of spans.
template <class Fn>
int32_t raster_triangle(const RasterVertex v[3], int32_t y_begin, int32_t y_end, int32_t x_limit, Fn&& fn) {
  // Sort by y; equal y keeps input order, which only decides which of two
  // horizontal-edge vertices is "top": such an edge covers no row.
  RasterVertex t = v[0], m = v[1], b = v[2];
  if (m.y < t.y) {
    const RasterVertex s = t;
    t = m;
    m = s;
  }
  if (b.y < m.y) {
    const RasterVertex s = m;
    m = b;
    b = s;
    if (m.y < t.y) {
      const RasterVertex s2 = t;
      t = m;
      m = s2;
    }
  }
  if (b.y == t.y) return 0;
  // Which side the middle vertex lies on, relative to the long edge t -> b.
  const int64_t cross = int64_t{m.x - t.x} * (b.y - t.y) - int64_t{m.y - t.y} * (b.x - t.x);
  if (cross == 0) return 0;
  const bool mid_right = cross > 0;

  const int32_t r_top = raster_row(t.y);
  const int32_t r_mid = raster_row(m.y);
  const int32_t r_bot = raster_row(b.y);
  int32_t y0 = r_top > y_begin ? r_top : y_begin;
  const int32_t y1 = r_bot < y_end ? r_bot : y_end;
  if (y0 >= y1) return 0;

  int32_t spans = 0;
  RasterEdge long_edge;
  long_edge.init(t, b, y0);
  auto run = [&](RasterEdge& shorter, int32_t from, int32_t to) {
    for (int32_t y = from; y < to; ++y) {
      int32_t xa = mid_right ? long_edge.x : shorter.x;
      int32_t xb = mid_right ? shorter.x : long_edge.x;
      if (xa < 0) xa = 0;
      if (xb > x_limit) xb = x_limit;
      if (xa < xb) {
        fn(y, xa, xb);
        ++spans;
      }
      long_edge.advance();
      shorter.advance();
    }
  };
  if (y0 < r_mid) {
    const int32_t to = r_mid < y1 ? r_mid : y1;
    RasterEdge upper;
    upper.init(t, m, y0);
    run(upper, y0, to);
    y0 = to;
  }
  if (y0 < y1) {
    RasterEdge lower;
    lower.init(m, b, y0);
    run(lower, y0, y1);
  }
  return spans;
}

// Calls fn(y, x_begin, x_end) for each non-empty span of the convex
// polygon v[0..n) (either orientation) in rows [y_begin, y_end), limited
// to x in [0, x_limit): one span a row, covering exactly the pixels the
// triangles of any fan of the polygon cover (every edge is walked as
// raster_triangle walks it, and a pixel on a diagonal belongs to one
// triangle of the two beside it). An outline made slightly concave by
// rounding is drawn between its leftmost and rightmost edges of each row.
// Vertices must satisfy kRasterCoordLimit. Returns the number of spans.
template <class Fn>
int32_t raster_convex(const RasterVertex* v, int n, int32_t y_begin, int32_t y_end, int32_t x_limit, Fn&& fn) {
  int top = 0, bot = 0;
  for (int i = 1; i < n; ++i) {
    if (v[i].y < v[top].y) top = i;
    if (v[i].y > v[bot].y) bot = i;
  }
  if (v[bot].y == v[top].y) return 0;
  int32_t y0 = raster_row(v[top].y) > y_begin ? raster_row(v[top].y) : y_begin;
  const int32_t y1 = raster_row(v[bot].y) < y_end ? raster_row(v[bot].y) : y_end;
  if (y0 >= y1) return 0;
  // The two chains from the top vertex to the bottom one, one each way
  // round; each holds the edge covering the current row.
  struct Chain {
    int at, next, dir;
    int32_t end;  // the first row past the edge
    RasterEdge e;
  };
  const auto seek = [&](Chain& c, int32_t row) {
    while (c.next != bot && raster_row(v[c.next].y) <= row) {
      c.at = c.next;
      c.next = (c.next + c.dir + n) % n;
    }
    c.end = raster_row(v[c.next].y);
    if (c.end > row) c.e.init(v[c.at], v[c.next], row);
  };
  Chain a{top, (top + 1) % n, 1, 0, {}}, b{top, (top + n - 1) % n, -1, 0, {}};
  seek(a, y0);
  seek(b, y0);
  int32_t spans = 0;
  for (int32_t y = y0; y < y1; ++y) {
    if (y >= a.end) seek(a, y);
    if (y >= b.end) seek(b, y);
    int32_t xa = a.e.x < b.e.x ? a.e.x : b.e.x;
    int32_t xb = a.e.x < b.e.x ? b.e.x : a.e.x;
    if (xa < 0) xa = 0;
    if (xb > x_limit) xb = x_limit;
    if (xa < xb) {
      fn(y, xa, xb);
      ++spans;
    }
    a.e.advance();
    b.e.advance();
  }
  return spans;
}

}  // namespace vds
