// vds encoder: rays against a scene (vds/enc/scene_rays.h). The hierarchy
// splits each node's triangles at the median of their centres along the
// longest axis of the centres' box, down to leaves of at most 4.
#include "vds/enc/scene_rays.h"

#include <algorithm>
#include <cmath>
#include <numeric>

namespace vds::enc {

namespace {

Vec3 sub(const Vec3& a, const Vec3& b) { return {a[0] - b[0], a[1] - b[1], a[2] - b[2]}; }
double dot(const Vec3& a, const Vec3& b) { return a[0] * b[0] + a[1] * b[1] + a[2] * b[2]; }
Vec3 cross(const Vec3& a, const Vec3& b) { return {a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]}; }

constexpr uint32_t kLeaf = 4;

}  // namespace

SceneRays::SceneRays(const Scene& s) {
  for (const SceneSurface& f : s.surfaces) {
    if (f.kind == SurfaceKind::fog || f.kind == SurfaceKind::additive) continue;
    for (uint32_t i = f.first_index; i + 2 < f.first_index + f.index_count; i += 3) {
      Vec3 p[3];
      for (int k = 0; k < 3; ++k) {
        const auto& v = s.vertices[s.indices[i + static_cast<uint32_t>(k)]].pos;
        p[k] = {v[0], v[1], v[2]};
      }
      tris_.push_back({p[0], sub(p[1], p[0]), sub(p[2], p[0])});
    }
  }
  if (tris_.empty()) return;
  std::vector<Vec3> centre(tris_.size());
  for (size_t i = 0; i < tris_.size(); ++i)
    for (int k = 0; k < 3; ++k) centre[i][k] = tris_[i].a[k] + (tris_[i].e1[k] + tris_[i].e2[k]) / 3;
  std::vector<uint32_t> order(tris_.size());
  std::iota(order.begin(), order.end(), 0u);
  // Iterative build: (node, first, count) ranges of `order`.
  struct Job {
    uint32_t node, first, count;
  };
  nodes_.push_back({});
  std::vector<Job> jobs{{0, 0, static_cast<uint32_t>(order.size())}};
  while (!jobs.empty()) {
    const Job j = jobs.back();
    jobs.pop_back();
    Node n{};
    n.lo = {INFINITY, INFINITY, INFINITY};
    n.hi = {-INFINITY, -INFINITY, -INFINITY};
    Vec3 clo{INFINITY, INFINITY, INFINITY}, chi{-INFINITY, -INFINITY, -INFINITY};
    for (uint32_t i = j.first; i < j.first + j.count; ++i) {
      const Tri& t = tris_[order[i]];
      for (int k = 0; k < 3; ++k) {
        const double v0 = t.a[k], v1 = t.a[k] + t.e1[k], v2 = t.a[k] + t.e2[k];
        n.lo[k] = std::min(n.lo[k], static_cast<float>(std::min({v0, v1, v2})) - 0.01f);
        n.hi[k] = std::max(n.hi[k], static_cast<float>(std::max({v0, v1, v2})) + 0.01f);
        clo[k] = std::min(clo[k], centre[order[i]][k]);
        chi[k] = std::max(chi[k], centre[order[i]][k]);
      }
    }
    if (j.count <= kLeaf) {
      n.first = j.first;
      n.count = j.count;
      nodes_[j.node] = n;
      continue;
    }
    int axis = 0;
    for (int k = 1; k < 3; ++k)
      if (chi[k] - clo[k] > chi[axis] - clo[axis]) axis = k;
    const uint32_t half = j.count / 2;
    std::nth_element(order.begin() + j.first, order.begin() + j.first + half, order.begin() + j.first + j.count,
                     [&](uint32_t a, uint32_t b) { return centre[a][axis] < centre[b][axis]; });
    n.first = static_cast<uint32_t>(nodes_.size());
    n.count = 0;
    nodes_[j.node] = n;
    nodes_.push_back({});
    nodes_.push_back({});
    jobs.push_back({n.first, j.first, half});
    jobs.push_back({n.first + 1, j.first + half, j.count - half});
  }
  // Leaves index triangles through `order`: store them in that order.
  std::vector<Tri> sorted(tris_.size());
  for (size_t i = 0; i < order.size(); ++i) sorted[i] = tris_[order[i]];
  tris_.swap(sorted);
}

double SceneRays::cast(const Vec3& o, const Vec3& d, double tmax) const {
  if (nodes_.empty()) return tmax;
  const Vec3 inv = {1 / d[0], 1 / d[1], 1 / d[2]};
  double best = tmax;
  uint32_t stack[64];
  int sp = 0;
  stack[sp++] = 0;
  while (sp > 0) {
    const Node& n = nodes_[stack[--sp]];
    // Slab test against the node's box.
    double t0 = 0, t1 = best;
    for (int k = 0; k < 3; ++k) {
      double a = (n.lo[k] - o[k]) * inv[k], b = (n.hi[k] - o[k]) * inv[k];
      if (std::isnan(a) || std::isnan(b)) {  // parallel, on the slab's edge
        if (o[k] < n.lo[k] || o[k] > n.hi[k]) t1 = -1;
        continue;
      }
      if (a > b) std::swap(a, b);
      t0 = std::max(t0, a);
      t1 = std::min(t1, b);
    }
    if (t0 > t1) continue;
    if (n.count == 0) {
      if (sp + 2 > 64) continue;  // deeper than any balanced tree of 2^62 triangles
      stack[sp++] = n.first;
      stack[sp++] = n.first + 1;
      continue;
    }
    for (uint32_t i = n.first; i < n.first + n.count; ++i) {
      const Tri& t = tris_[i];
      const Vec3 p = cross(d, t.e2);
      const double det = dot(t.e1, p);
      if (std::fabs(det) < 1e-12) continue;
      const double id = 1 / det;
      const Vec3 s = sub(o, t.a);
      const double u = dot(s, p) * id;
      if (u < 0 || u > 1) continue;
      const Vec3 q = cross(s, t.e1);
      const double v = dot(d, q) * id;
      if (v < 0 || u + v > 1) continue;
      const double tt = dot(t.e2, q) * id;
      if (tt >= 0 && tt < best) best = tt;
    }
  }
  return best;
}

double SceneRays::clearance(const Vec3& p, double limit, double enough) const {
  double nearest = limit;
  for (int x = -1; x <= 1; ++x)
    for (int y = -1; y <= 1; ++y)
      for (int z = -1; z <= 1; ++z) {
        if (x == 0 && y == 0 && z == 0) continue;
        const double l = std::sqrt(static_cast<double>(x * x + y * y + z * z));
        nearest = std::min(nearest, cast(p, {x / l, y / l, z / l}, nearest));
        if (nearest < enough) return nearest;
      }
  return nearest;
}

bool SceneRays::clear(const Vec3& p, double radius) const { return clearance(p, radius, radius) >= radius; }

bool SceneRays::segment_clear(const Vec3& a, const Vec3& b, double radius) const {
  if (!clear(a, radius) || !clear(b, radius)) return false;
  const Vec3 d = sub(b, a);
  const double len = std::sqrt(dot(d, d));
  if (len == 0) return true;
  const Vec3 dir = {d[0] / len, d[1] / len, d[2] / len};
  // Sideways: horizontal across the direction, and up across both.
  Vec3 side = cross(dir, {0, 0, 1});
  double sl = std::sqrt(dot(side, side));
  if (sl < 1e-6) side = {1, 0, 0}, sl = 1;
  side = {side[0] / sl, side[1] / sl, side[2] / sl};
  const Vec3 up = cross(side, dir);
  const Vec3 offsets[5] = {{0, 0, 0}, side, {-side[0], -side[1], -side[2]}, up, {-up[0], -up[1], -up[2]}};
  for (const Vec3& off : offsets) {
    const Vec3 o = {a[0] + off[0] * radius, a[1] + off[1] * radius, a[2] + off[2] * radius};
    if (cast(o, dir, len) < len) return false;
  }
  return true;
}

}  // namespace vds::enc
