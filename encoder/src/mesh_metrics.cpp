// vds encoder: symmetric surface distance by sampling (Metro-style, Cignoni
// et al. 1998) with a uniform grid of triangles for the nearest-point search.
#include "vds/enc/mesh_metrics.h"

#include <algorithm>
#include <cmath>
#include <random>
#include <vector>

#include "vds/enc/mesh_simplify.h"

namespace vds::enc {
namespace {

using Vec = std::array<double, 3>;

class TriangleGrid {
 public:
  explicit TriangleGrid(const Mesh& m) : m_(m) {
    const Bounds b = mesh_bounds(m);
    lo_ = b.min;
    const double extent = std::max(b.max_extent(), 1e-12);
    // About two triangles per occupied cell on a surface.
    const double cells = std::max(1.0, std::sqrt(static_cast<double>(m.triangles.size()) / 2.0));
    cell_ = extent / cells;
    for (int k = 0; k < 3; ++k)
      n_[k] = std::max(1, static_cast<int>(std::ceil((b.max[k] - b.min[k]) / cell_ + 1e-9)));
    bins_.resize(static_cast<size_t>(n_[0]) * n_[1] * n_[2]);
    for (uint32_t t = 0; t < m.triangles.size(); ++t) {
      int c0[3], c1[3];
      for (int k = 0; k < 3; ++k) {
        double mn = INFINITY, mx = -INFINITY;
        for (uint32_t v : m.triangles[t]) {
          mn = std::min(mn, m.positions[v][k]);
          mx = std::max(mx, m.positions[v][k]);
        }
        c0[k] = clampi(static_cast<int>(std::floor((mn - lo_[k]) / cell_)), k);
        c1[k] = clampi(static_cast<int>(std::floor((mx - lo_[k]) / cell_)), k);
      }
      for (int z = c0[2]; z <= c1[2]; ++z)
        for (int y = c0[1]; y <= c1[1]; ++y)
          for (int x = c0[0]; x <= c1[0]; ++x) bins_[index(x, y, z)].push_back(t);
    }
  }

  // Squared distance from p to the nearest triangle.
  double nearest2(const Vec& p) const {
    int c[3];
    for (int k = 0; k < 3; ++k) c[k] = clampi(static_cast<int>(std::floor((p[k] - lo_[k]) / cell_)), k);
    double best = INFINITY;
    const int max_ring = std::max({n_[0], n_[1], n_[2]});
    for (int r = 0; r <= max_ring; ++r) {
      // Ring r and beyond lie outside the block of rings < r: nothing there
      // is nearer than that block's boundary.
      if (r > 0 && outside_distance2(p, c, r - 1) >= best) break;
      for (int z = c[2] - r; z <= c[2] + r; ++z)
        for (int y = c[1] - r; y <= c[1] + r; ++y)
          for (int x = c[0] - r; x <= c[0] + r; ++x) {
            if (std::max({std::abs(x - c[0]), std::abs(y - c[1]), std::abs(z - c[2])}) != r) continue;
            if (x < 0 || y < 0 || z < 0 || x >= n_[0] || y >= n_[1] || z >= n_[2]) continue;
            for (uint32_t t : bins_[index(x, y, z)]) {
              const auto& tri = m_.triangles[t];
              best = std::min(best, point_triangle_distance2(p, m_.positions[tri[0]], m_.positions[tri[1]],
                                                             m_.positions[tri[2]]));
            }
          }
    }
    return best;
  }

 private:
  int clampi(int v, int k) const { return std::clamp(v, 0, n_[k] - 1); }
  size_t index(int x, int y, int z) const {
    return (static_cast<size_t>(z) * n_[1] + static_cast<size_t>(y)) * n_[0] + static_cast<size_t>(x);
  }
  // Squared distance from p to anything outside the box of cells within
  // Chebyshev radius r of c (0 if p is not inside that box).
  double outside_distance2(const Vec& p, const int c[3], int r) const {
    double inner = INFINITY;
    for (int k = 0; k < 3; ++k) {
      const double lo = lo_[k] + (c[k] - r) * cell_, hi = lo_[k] + (c[k] + r + 1) * cell_;
      if (p[k] < lo || p[k] > hi) return 0;
      inner = std::min({inner, p[k] - lo, hi - p[k]});
    }
    return inner * inner;
  }

  const Mesh& m_;
  Vec lo_{};
  double cell_ = 1;
  int n_[3] = {1, 1, 1};
  std::vector<std::vector<uint32_t>> bins_;
};

std::vector<Vec> sample(const Mesh& m, size_t samples, uint32_t seed) {
  std::vector<Vec> pts(m.positions.begin(), m.positions.end());
  std::vector<double> cum;
  double total = 0;
  for (const auto& t : m.triangles) {
    const Vec& a = m.positions[t[0]];
    const Vec& b = m.positions[t[1]];
    const Vec& c = m.positions[t[2]];
    const Vec e1{b[0] - a[0], b[1] - a[1], b[2] - a[2]}, e2{c[0] - a[0], c[1] - a[1], c[2] - a[2]};
    const Vec n{e1[1] * e2[2] - e1[2] * e2[1], e1[2] * e2[0] - e1[0] * e2[2], e1[0] * e2[1] - e1[1] * e2[0]};
    total += 0.5 * std::sqrt(n[0] * n[0] + n[1] * n[1] + n[2] * n[2]);
    cum.push_back(total);
  }
  if (total <= 0 || m.triangles.empty()) return pts;
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> u01(0.0, 1.0);
  for (size_t i = 0; i < samples; ++i) {
    const size_t t = static_cast<size_t>(std::lower_bound(cum.begin(), cum.end(), u01(rng) * total) - cum.begin());
    const auto& tri = m.triangles[std::min(t, m.triangles.size() - 1)];
    double r1 = u01(rng), r2 = u01(rng);
    if (r1 + r2 > 1) {
      r1 = 1 - r1;
      r2 = 1 - r2;
    }
    Vec p;
    for (int k = 0; k < 3; ++k)
      p[k] = m.positions[tri[0]][k] + r1 * (m.positions[tri[1]][k] - m.positions[tri[0]][k]) +
             r2 * (m.positions[tri[2]][k] - m.positions[tri[0]][k]);
    pts.push_back(p);
  }
  return pts;
}

}  // namespace

SurfaceDistance surface_distance(const Mesh& a, const Mesh& b, size_t samples, uint32_t seed) {
  SurfaceDistance d;
  if (a.triangles.empty() || b.triangles.empty()) return d;
  const TriangleGrid ga(a), gb(b);
  double sum2 = 0, sum = 0;
  size_t n = 0;
  for (const Vec& p : sample(a, samples, seed)) {
    const double d2 = gb.nearest2(p);
    d.max_ab = std::max(d.max_ab, std::sqrt(d2));
    sum2 += d2;
    sum += std::sqrt(d2);
    ++n;
  }
  for (const Vec& p : sample(b, samples, seed + 1)) {
    const double d2 = ga.nearest2(p);
    d.max_ba = std::max(d.max_ba, std::sqrt(d2));
    sum2 += d2;
    sum += std::sqrt(d2);
    ++n;
  }
  d.hausdorff = std::max(d.max_ab, d.max_ba);
  d.rms = n ? std::sqrt(sum2 / static_cast<double>(n)) : 0;
  d.mean = n ? sum / static_cast<double>(n) : 0;
  return d;
}

}  // namespace vds::enc
