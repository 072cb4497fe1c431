// Test meshes for the mesh codec tests, generated in code: an open grid
// patch (boundary), the same with a hole, an icosphere, a torus (genus 1),
// and helpers to combine and perturb them. Deterministic for a given seed.
#pragma once
#include <array>
#include <cmath>
#include <cstdint>
#include <random>
#include <vector>

#include "vds/enc/mesh_import.h"

namespace vds::test {

using enc::Mesh;

// nx × ny vertices on a gently curved sheet, two triangles per cell.
inline Mesh grid_mesh(int nx, int ny, double noise = 0.0, uint32_t seed = 1) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> jitter(-noise, noise);
  Mesh m;
  for (int y = 0; y < ny; ++y)
    for (int x = 0; x < nx; ++x) {
      const double u = double(x) / (nx - 1), v = double(y) / (ny - 1);
      m.positions.push_back({u + jitter(rng) / nx, v + jitter(rng) / ny,
                             0.2 * std::sin(3.0 * u) * std::cos(2.0 * v) + jitter(rng) / nx});
    }
  for (int y = 0; y + 1 < ny; ++y)
    for (int x = 0; x + 1 < nx; ++x) {
      const uint32_t a = y * nx + x, b = a + 1, c = a + nx, d = c + 1;
      m.triangles.push_back({a, b, d});
      m.triangles.push_back({a, d, c});
    }
  return m;
}

// Removes the faces whose centroid is within `radius` of (cx, cy) and the
// vertices left unused: a grid with a hole.
inline Mesh with_hole(const Mesh& in, double cx, double cy, double radius) {
  Mesh m;
  std::vector<int64_t> remap(in.positions.size(), -1);
  for (const auto& t : in.triangles) {
    double x = 0, y = 0;
    for (uint32_t v : t) {
      x += in.positions[v][0] / 3;
      y += in.positions[v][1] / 3;
    }
    if ((x - cx) * (x - cx) + (y - cy) * (y - cy) < radius * radius) continue;
    std::array<uint32_t, 3> nt{};
    for (int k = 0; k < 3; ++k) {
      if (remap[t[k]] < 0) {
        remap[t[k]] = static_cast<int64_t>(m.positions.size());
        m.positions.push_back(in.positions[t[k]]);
      }
      nt[k] = static_cast<uint32_t>(remap[t[k]]);
    }
    m.triangles.push_back(nt);
  }
  return m;
}

// Icosahedron subdivided `levels` times (4-to-1), on a bumpy sphere.
inline Mesh sphere_mesh(int levels, double bump = 0.05, uint32_t seed = 2) {
  const double t = (1.0 + std::sqrt(5.0)) / 2.0;
  Mesh m;
  m.positions = {{-1, t, 0}, {1, t, 0}, {-1, -t, 0}, {1, -t, 0}, {0, -1, t}, {0, 1, t},
                 {0, -1, -t}, {0, 1, -t}, {t, 0, -1}, {t, 0, 1}, {-t, 0, -1}, {-t, 0, 1}};
  m.triangles = {{0, 11, 5}, {0, 5, 1},  {0, 1, 7},   {0, 7, 10}, {0, 10, 11}, {1, 5, 9}, {5, 11, 4},
                 {11, 10, 2}, {10, 7, 6}, {7, 1, 8},  {3, 9, 4},  {3, 4, 2},   {3, 2, 6}, {3, 6, 8},
                 {3, 8, 9},  {4, 9, 5},  {2, 4, 11}, {6, 2, 10}, {8, 6, 7},   {9, 8, 1}};
  for (int l = 0; l < levels; ++l) {
    std::vector<std::array<uint32_t, 3>> next;
    std::vector<std::pair<uint64_t, uint32_t>> mids;
    auto mid = [&](uint32_t a, uint32_t b) {
      const uint64_t key = a < b ? (uint64_t{a} << 32 | b) : (uint64_t{b} << 32 | a);
      for (const auto& e : mids)
        if (e.first == key) return e.second;
      const auto& pa = m.positions[a];
      const auto& pb = m.positions[b];
      m.positions.push_back({(pa[0] + pb[0]) / 2, (pa[1] + pb[1]) / 2, (pa[2] + pb[2]) / 2});
      mids.emplace_back(key, static_cast<uint32_t>(m.positions.size() - 1));
      return static_cast<uint32_t>(m.positions.size() - 1);
    };
    for (const auto& f : m.triangles) {
      const uint32_t ab = mid(f[0], f[1]), bc = mid(f[1], f[2]), ca = mid(f[2], f[0]);
      next.push_back({f[0], ab, ca});
      next.push_back({f[1], bc, ab});
      next.push_back({f[2], ca, bc});
      next.push_back({ab, bc, ca});
    }
    m.triangles.swap(next);
  }
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> jitter(-bump, bump);
  for (auto& p : m.positions) {
    const double r = std::sqrt(p[0] * p[0] + p[1] * p[1] + p[2] * p[2]);
    const double s = (1.0 + 0.3 * std::sin(3 * p[0]) * std::cos(2 * p[1]) + jitter(rng)) / r;
    for (double& c : p) c *= s;
  }
  return m;
}

// Torus of nu × nv vertices (genus 1, closed).
inline Mesh torus_mesh(int nu, int nv) {
  Mesh m;
  const double pi = 3.14159265358979323846;
  for (int i = 0; i < nu; ++i)
    for (int j = 0; j < nv; ++j) {
      const double a = 2 * pi * i / nu, b = 2 * pi * j / nv;
      const double r = 1.0 + 0.35 * std::cos(b);
      m.positions.push_back({r * std::cos(a), r * std::sin(a), 0.35 * std::sin(b) + 0.02 * std::sin(5 * a)});
    }
  for (int i = 0; i < nu; ++i)
    for (int j = 0; j < nv; ++j) {
      const uint32_t a = i * nv + j, b = ((i + 1) % nu) * nv + j, c = i * nv + (j + 1) % nv,
                     d = ((i + 1) % nu) * nv + (j + 1) % nv;
      m.triangles.push_back({a, b, d});
      m.triangles.push_back({a, d, c});
    }
  return m;
}

// Both meshes in one (separate components), the second shifted along x.
inline Mesh combine(const Mesh& a, const Mesh& b, double shift = 3.0) {
  Mesh m = a;
  const uint32_t base = static_cast<uint32_t>(m.positions.size());
  for (auto p : b.positions) {
    p[0] += shift;
    m.positions.push_back(p);
  }
  for (const auto& t : b.triangles) m.triangles.push_back({t[0] + base, t[1] + base, t[2] + base});
  return m;
}

}  // namespace vds::test
