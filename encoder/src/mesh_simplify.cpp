// vds encoder: progressive simplification by independent sets of half-edge
// collapses (Qin, Liu, Bao, Peng 2002, section 2); the rules are listed in
// vds/enc/mesh_simplify.h.
#include "vds/enc/mesh_simplify.h"

#include <algorithm>
#include <cmath>
#include <numeric>
#include <stdexcept>
#include <cstdlib>
#include <functional>

#include "vds/enc/mesh_import.h"

namespace vds::enc {
namespace {

using Vec = std::array<double, 3>;
using Tri = std::array<uint32_t, 3>;

Vec sub(const Vec& a, const Vec& b) { return {a[0] - b[0], a[1] - b[1], a[2] - b[2]}; }
Vec cross(const Vec& a, const Vec& b) {
  return {a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]};
}
double dot(const Vec& a, const Vec& b) { return a[0] * b[0] + a[1] * b[1] + a[2] * b[2]; }
double norm(const Vec& a) { return std::sqrt(dot(a, a)); }

class Simplifier {
 public:
  Simplifier(const std::vector<std::array<int32_t, 3>>& positions, const std::vector<Tri>& triangles,
             const SimplifyOptions& o)
      : opt_(o) {
    P_.resize(positions.size());
    for (size_t i = 0; i < positions.size(); ++i)
      P_[i] = {double(positions[i][0]), double(positions[i][1]), double(positions[i][2])};
    F_ = triangles;
    falive_.assign(F_.size(), 1);
    valive_.assign(P_.size(), 1);
    vf_.resize(P_.size());
    for (uint32_t f = 0; f < F_.size(); ++f)
      for (uint32_t v : F_[f]) vf_[v].push_back(f);
    fpts_.resize(F_.size());
    alive_count_ = P_.size();
  }

  SimplifyResult run() {
    SimplifyResult res;
    std::array<double, 3> lo = P_.empty() ? Vec{0, 0, 0} : P_[0], hi = lo;
    for (const Vec& p : P_)
      for (int k = 0; k < 3; ++k) {
        lo[k] = std::min(lo[k], p[k]);
        hi[k] = std::max(hi[k], p[k]);
      }
    const double diag = norm(sub(hi, lo));
    res.error_limit = opt_.max_error * diag;
    int S = opt_.steps;
    if (S <= 0) {
      const double ratio = std::clamp(opt_.target_base_ratio, 1e-6, 0.999);
      S = static_cast<int>(std::ceil(std::log(1.0 / ratio) / std::log(4.0 / 3.0)));
      S = std::max(S, 1);
    }
    res.steps = S;
    for (uint32_t v = 0; v < P_.size(); ++v) res.max_degree_seen = std::max(res.max_degree_seen, int(degree(v)));

    int k = 1;
    std::vector<char> locked(P_.size(), 0), target(P_.size(), 0);
    while (true) {
      if (opt_.max_levels > 0 && static_cast<int>(res.levels.size()) >= opt_.max_levels) break;
      if (alive_count_ <= opt_.min_base_vertices) break;
      SimplifyLevel level;
      level.vertices_before = alive_count_;
      std::fill(locked.begin(), locked.end(), 0);
      std::fill(target.begin(), target.end(), 0);
      const double need = opt_.removal_ratio * static_cast<double>(alive_count_);
      bool exhausted = false;
      while (true) {
        const double threshold = res.error_limit * k / S;
        level.threshold = threshold;
        pass(threshold, locked, target, level, res.max_degree_seen);
        if (static_cast<double>(level.collapses.size()) >= need) break;
        if (k >= S) {
          exhausted = true;
          break;
        }
        ++k;
      }
      if (level.collapses.empty()) break;
      level.max_distance = max_distance_;
      const double removed = static_cast<double>(level.collapses.size());
      const double before = static_cast<double>(level.vertices_before);
      res.levels.push_back(std::move(level));
      // With the whole error budget in force, levels go on while the
      // manifold and independence constraints still let a useful share go,
      // or while the base is above its target size.
      const bool base_too_big = static_cast<double>(alive_count_) > opt_.target_base_ratio * double(P_.size());
      if (exhausted && removed < opt_.tail_removal_ratio * before && !base_too_big) break;
    }
    for (uint32_t v = 0; v < P_.size(); ++v)
      if (valive_[v]) res.base_vertices.push_back(v);
    for (uint32_t f = 0; f < F_.size(); ++f)
      if (falive_[f]) res.base_triangles.push_back(F_[f]);
    return res;
  }

 private:
  size_t degree(uint32_t v) {
    ring(v, ring_tmp_);
    return ring_tmp_.size();
  }

  // Ring of v counter-clockwise; returns true if v is on the boundary (then
  // the ring is a path from the first to the last neighbour).
  bool ring(uint32_t v, std::vector<uint32_t>& out) {
    out.clear();
    pairs_.clear();
    for (uint32_t f : vf_[v]) {
      const Tri& t = F_[f];
      const int i = t[0] == v ? 0 : (t[1] == v ? 1 : 2);
      pairs_.emplace_back(t[(i + 1) % 3], t[(i + 2) % 3]);
    }
    if (pairs_.empty()) return false;
    // A path starts at an `a` that is nobody's `b`.
    size_t start = 0;
    bool boundary = false;
    for (size_t i = 0; i < pairs_.size(); ++i) {
      bool is_b = false;
      for (const auto& q : pairs_)
        if (q.second == pairs_[i].first) is_b = true;
      if (!is_b) {
        start = i;
        boundary = true;
        break;
      }
    }
    uint32_t cur = pairs_[start].first;
    out.push_back(cur);
    for (size_t step = 0; step < pairs_.size(); ++step) {
      bool found = false;
      for (const auto& q : pairs_)
        if (q.first == cur) {
          cur = q.second;
          found = true;
          break;
        }
      if (!found) break;
      if (!boundary && step + 1 == pairs_.size()) break;  // back at the start
      out.push_back(cur);
    }
    return boundary;
  }

  double priority(uint32_t v) {
    const bool on_boundary = ring(v, ring_tmp_);
    double mn = INFINITY, mx = 0;
    for (uint32_t w : ring_tmp_) {
      const double e = norm(sub(P_[w], P_[v]));
      mn = std::min(mn, e);
      mx = std::max(mx, e);
    }
    double pr = opt_.alpha * mn + opt_.beta * mx;
    if (opt_.rate_weight > 0) {
      Vec c{0, 0, 0};
      for (size_t j = 0; j < ring_tmp_.size(); ++j)
        for (int k = 0; k < 3; ++k) c[k] += P_[ring_tmp_[j]][k];
      for (int k = 0; k < 3; ++k) c[k] /= double(ring_tmp_.size());
      if (opt_.area_centroid && !on_boundary) c = area_centroid(c);
      // v's distance from where the client will predict it is what coding
      // v costs at this level: cheap vertices go first.
      pr += opt_.rate_weight * norm(sub(P_[v], c));
    }
    return pr;
  }

  // The area centroid of the closed ring in ring_tmp_ (fan around its
  // vertex centroid c), as the client's area predictor places v.
  Vec area_centroid(const Vec& c) {
    Vec acc{0, 0, 0};
    double total = 0;
    const size_t d = ring_tmp_.size();
    for (size_t j = 0; j < d; ++j) {
      const Vec& a = P_[ring_tmp_[j]];
      const Vec& b = P_[ring_tmp_[(j + 1) % d]];
      const Vec x = cross(sub(a, c), sub(b, c));
      const double w = std::max({std::fabs(x[0]), std::fabs(x[1]), std::fabs(x[2])});
      total += w;
      for (int k = 0; k < 3; ++k) acc[k] += w * (a[k] + b[k] + c[k]) / 3;
    }
    if (total <= 0) return c;
    for (int k = 0; k < 3; ++k) acc[k] /= total;
    return acc;
  }

  // Cone volume of collapsing v onto its ring vertex at index k (eq. 2).
  double cone_volume(uint32_t v, const std::vector<uint32_t>& r, bool boundary, size_t k) {
    const Vec& uk = P_[r[k]];
    const Vec d = sub(P_[v], uk);
    double vol = 0;
    const size_t n = r.size();
    const size_t faces = boundary ? n - 1 : n;
    for (size_t j = 0; j < faces; ++j) {
      const Vec a = sub(P_[r[j]], uk), b = sub(P_[r[(j + 1) % n]], uk);
      vol += dot(cross(a, b), d);
    }
    return std::fabs(vol);
  }

  // Tries v -> u; if allowed, performs it and fills `c`.
  bool try_collapse(uint32_t v, uint32_t u, const std::vector<uint32_t>& rv, bool v_boundary, double threshold,
                    Collapse& c, int& max_deg) {
    const size_t n = rv.size();
    size_t p = 0;
    while (p < n && rv[p] != u) ++p;
    if (p == n) return false;
    int64_t wf = -1, wl = -1;
    if (v_boundary) {
      if (p == 0)
        wf = rv[1];
      else if (p == n - 1)
        wl = rv[n - 2];
      else
        return false;  // interior edge between two boundary vertices would pinch
    } else {
      wf = rv[(p + 1) % n];
      wl = rv[(p + n - 1) % n];
    }
    std::vector<uint32_t> ru;
    const bool u_boundary = ring(u, ru);
    // Link condition: the common neighbours of u and v are exactly the wings.
    size_t common = 0;
    for (uint32_t a : rv)
      for (uint32_t b : ru)
        if (a == b) {
          if (static_cast<int64_t>(a) != wf && static_cast<int64_t>(a) != wl) return false;
          ++common;
        }
    if (common != static_cast<size_t>((wf >= 0) + (wl >= 0))) return false;
    // Wings keep enough faces: an interior wing needs degree >= 3 after,
    // a boundary wing at least one face.
    for (int64_t w : {wf, wl}) {
      if (w < 0) continue;
      std::vector<uint32_t> rw;
      const bool wb = ring(static_cast<uint32_t>(w), rw);
      if (!wb && rw.size() < 4) return false;
      if (wb && vf_[w].size() < 2) return false;
    }
    // Degree of u after the collapse.
    const size_t new_deg = ru.size() + rv.size() - 2 - common;
    if (static_cast<int>(new_deg) > opt_.max_degree) return false;
    if (!u_boundary && new_deg < 3) return false;
    // Faces: moved (v replaced by u) and removed (contain u).
    moved_.clear();
    removed_.clear();
    for (uint32_t f : vf_[v]) {
      const Tri& t = F_[f];
      if (t[0] == u || t[1] == u || t[2] == u)
        removed_.push_back(f);
      else
        moved_.push_back(f);
    }
    // No face turns over.
    for (uint32_t f : moved_) {
      Tri t = F_[f];
      const Vec n0 = cross(sub(P_[t[1]], P_[t[0]]), sub(P_[t[2]], P_[t[0]]));
      for (uint32_t& x : t)
        if (x == v) x = u;
      const Vec n1 = cross(sub(P_[t[1]], P_[t[0]]), sub(P_[t[2]], P_[t[0]]));
      const double l0 = dot(n0, n0);
      if (l0 > 0 && dot(n0, n1) <= 0) return false;
    }
    // Distance check: v and every original vertex carried by v's faces must
    // stay within the threshold of u's new fan.
    fan_.clear();
    for (uint32_t f : vf_[u])
      if (std::find(removed_.begin(), removed_.end(), f) == removed_.end()) fan_.push_back(F_[f]);
    for (uint32_t f : moved_) {
      Tri t = F_[f];
      for (uint32_t& x : t)
        if (x == v) x = u;
      fan_.push_back(t);
    }
    fan_ids_.clear();
    for (uint32_t f : vf_[u])
      if (std::find(removed_.begin(), removed_.end(), f) == removed_.end()) fan_ids_.push_back(f);
    for (uint32_t f : moved_) fan_ids_.push_back(f);
    pts_.clear();
    pts_.push_back(v);
    for (uint32_t f : vf_[v]) pts_.insert(pts_.end(), fpts_[f].begin(), fpts_[f].end());
    assign_.resize(pts_.size());
    const double t2 = threshold * threshold;
    double worst = 0;
    for (size_t i = 0; i < pts_.size(); ++i) {
      double best = INFINITY;
      size_t bi = 0;
      for (size_t j = 0; j < fan_.size(); ++j) {
        const double d = point_triangle_distance2(P_[pts_[i]], P_[fan_[j][0]], P_[fan_[j][1]], P_[fan_[j][2]]);
        if (d < best) {
          best = d;
          bi = j;
        }
      }
      if (best > t2) return false;
      worst = std::max(worst, best);
      assign_[i] = fan_ids_[bi];
    }
    // Perform.
    for (uint32_t f : removed_) {
      falive_[f] = 0;
      for (uint32_t x : F_[f]) {
        if (x == v) continue;
        auto& l = vf_[x];
        l.erase(std::find(l.begin(), l.end(), f));
      }
    }
    for (uint32_t f : vf_[v]) fpts_[f].clear();
    for (uint32_t f : moved_) {
      for (uint32_t& x : F_[f])
        if (x == v) x = u;
      vf_[u].push_back(f);
    }
    vf_[v].clear();
    valive_[v] = 0;
    --alive_count_;
    for (size_t i = 0; i < pts_.size(); ++i) fpts_[assign_[i]].push_back(pts_[i]);
    max_distance_ = std::max(max_distance_, std::sqrt(worst));
    max_deg = std::max(max_deg, static_cast<int>(new_deg));
    c.v = v;
    c.u = u;
    c.wing_f = wf;
    c.wing_l = wl;
    return true;
  }

  // Unlocked live neighbours of v: what removing v takes from this level.
  uint32_t residual(uint32_t v, const std::vector<char>& locked) {
    ring(v, ring_tmp_);
    uint32_t n = 0;
    for (uint32_t w : ring_tmp_)
      if (valive_[w] && !locked[w]) ++n;
    return n;
  }

  void pass(double threshold, std::vector<char>& locked, std::vector<char>& target, SimplifyLevel& level,
            int& max_deg) {
    std::vector<std::pair<double, uint32_t>> order;
    for (uint32_t v = 0; v < P_.size(); ++v)
      if (valive_[v] && !locked[v] && !vf_[v].empty()) order.emplace_back(priority(v), v);
    std::sort(order.begin(), order.end());
    // Visiting order: by priority rank (0..1), plus packing_weight per
    // unlocked neighbour the removal would lock. Vertices whose
    // neighbourhood is already mostly locked waste least of the level, so
    // a positive weight packs larger independent sets.
    const double pw = opt_.packing_weight;
    std::vector<double> rank(P_.size(), 0);
    for (size_t i = 0; i < order.size(); ++i) rank[order[i].second] = double(i) / double(order.size());
    struct Entry {
      double key;
      uint32_t v;
      uint32_t res;
      bool operator>(const Entry& o) const { return key > o.key || (key == o.key && v > o.v); }
    };
    std::vector<Entry> heap;
    std::vector<char> tried(pw > 0 ? P_.size() : 0, 0);
    for (const auto& e : order) {
      const uint32_t res = pw > 0 ? residual(e.second, locked) : 0;
      heap.push_back({rank[e.second] + pw * res, e.second, res});
    }
    std::make_heap(heap.begin(), heap.end(), std::greater<Entry>());
    std::vector<uint32_t> rv, rw;
    std::vector<std::pair<double, size_t>> cand;
    while (!heap.empty()) {
      std::pop_heap(heap.begin(), heap.end(), std::greater<Entry>());
      const Entry top = heap.back();
      heap.pop_back();
      const uint32_t v = top.v;
      if (locked[v] || !valive_[v]) continue;
      if (pw > 0) {
        if (tried[v]) continue;
        if (residual(v, locked) != top.res) continue;  // a fresher entry is queued
        tried[v] = 1;
      }
      if (alive_count_ <= opt_.min_base_vertices) return;
      const bool vb = ring(v, rv);
      cand.clear();
      for (size_t k = 0; k < rv.size(); ++k) {
        if (target[rv[k]]) continue;
        const double cost = cone_volume(v, rv, vb, k);
        cand.emplace_back(cost, k);
      }
      std::sort(cand.begin(), cand.end());
      for (const auto& entry : cand) {
        const size_t k = entry.second;
        Collapse c;
        const std::vector<uint32_t> ring_before = rv;
        if (try_collapse(v, rv[k], rv, vb, threshold, c, max_deg)) {
          level.collapses.push_back(c);
          for (uint32_t w : ring_before) locked[w] = 1;
          locked[v] = 1;
          target[c.u] = 1;
          if (pw > 0) {
            // The neighbours of the newly locked vertices lost candidates
            // around them: queue them again with their smaller key.
            for (uint32_t w : ring_before) {
              ring(w, rw);
              for (uint32_t x : rw) {
                if (!valive_[x] || locked[x] || tried[x] || vf_[x].empty()) continue;
                const uint32_t res = residual(x, locked);
                heap.push_back({rank[x] + pw * res, x, res});
                std::push_heap(heap.begin(), heap.end(), std::greater<Entry>());
              }
            }
          }
          break;
        }
      }
    }
  }

  SimplifyOptions opt_;
  std::vector<Vec> P_;
  std::vector<Tri> F_;
  std::vector<char> falive_, valive_;
  std::vector<std::vector<uint32_t>> vf_;
  std::vector<std::vector<uint32_t>> fpts_;
  size_t alive_count_ = 0;
  double max_distance_ = 0;
  // scratch
  std::vector<std::pair<uint32_t, uint32_t>> pairs_;
  std::vector<uint32_t> ring_tmp_, moved_, removed_, pts_, fan_ids_;
  std::vector<Tri> fan_;
  std::vector<uint32_t> assign_;
};

}  // namespace

double point_triangle_distance2(const std::array<double, 3>& p, const std::array<double, 3>& a,
                                const std::array<double, 3>& b, const std::array<double, 3>& c) {
  // Closest point by Voronoi regions of the triangle.
  const Vec ab = sub(b, a), ac = sub(c, a), ap = sub(p, a);
  auto d2 = [&p](const Vec& q) {
    const Vec d = sub(p, q);
    return dot(d, d);
  };
  const double d1 = dot(ab, ap), d2v = dot(ac, ap);
  if (d1 <= 0 && d2v <= 0) return d2(a);
  const Vec bp = sub(p, b);
  const double d3 = dot(ab, bp), d4 = dot(ac, bp);
  if (d3 >= 0 && d4 <= d3) return d2(b);
  const double vc = d1 * d4 - d3 * d2v;
  if (vc <= 0 && d1 >= 0 && d3 <= 0) {
    const double t = d1 / (d1 - d3);
    return d2({a[0] + t * ab[0], a[1] + t * ab[1], a[2] + t * ab[2]});
  }
  const Vec cp = sub(p, c);
  const double d5 = dot(ab, cp), d6 = dot(ac, cp);
  if (d6 >= 0 && d5 <= d6) return d2(c);
  const double vb = d5 * d2v - d1 * d6;
  if (vb <= 0 && d2v >= 0 && d6 <= 0) {
    const double t = d2v / (d2v - d6);
    return d2({a[0] + t * ac[0], a[1] + t * ac[1], a[2] + t * ac[2]});
  }
  const double va = d3 * d6 - d5 * d4;
  if (va <= 0 && (d4 - d3) >= 0 && (d5 - d6) >= 0) {
    const double t = (d4 - d3) / ((d4 - d3) + (d5 - d6));
    return d2({b[0] + t * (c[0] - b[0]), b[1] + t * (c[1] - b[1]), b[2] + t * (c[2] - b[2])});
  }
  const double sum = va + vb + vc;
  if (!(sum > 0)) {
    // Degenerate triangle: the nearest of its three edges.
    auto seg = [&](const Vec& s0, const Vec& s1) {
      const Vec d = sub(s1, s0);
      const double len2 = dot(d, d);
      double t = len2 > 0 ? dot(sub(p, s0), d) / len2 : 0;
      t = std::clamp(t, 0.0, 1.0);
      return d2({s0[0] + t * d[0], s0[1] + t * d[1], s0[2] + t * d[2]});
    };
    return std::min({seg(a, b), seg(b, c), seg(c, a)});
  }
  const double denom = 1.0 / sum;
  const double v = vb * denom, w = vc * denom;
  return d2({a[0] + ab[0] * v + ac[0] * w, a[1] + ab[1] * v + ac[1] * w, a[2] + ab[2] * v + ac[2] * w});
}

SimplifyResult simplify_progressive(const std::vector<std::array<int32_t, 3>>& positions,
                                    const std::vector<std::array<uint32_t, 3>>& triangles,
                                    const SimplifyOptions& options) {
  Mesh m;
  m.positions.resize(positions.size());
  for (size_t i = 0; i < positions.size(); ++i)
    m.positions[i] = {double(positions[i][0]), double(positions[i][1]), double(positions[i][2])};
  m.triangles = triangles;
  const std::string why = check_manifold(m);
  if (!why.empty()) throw std::invalid_argument("simplify_progressive: mesh is not manifold: " + why);
  Simplifier s(positions, triangles, options);
  return s.run();
}

}  // namespace vds::enc
