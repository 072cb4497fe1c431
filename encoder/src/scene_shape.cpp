// vds encoder: a scene's shape in fewer triangles (vds/enc/scene_shape.h).
#include "vds/enc/scene_shape.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <map>
#include <unordered_map>
#include <vector>

#include <meshoptimizer.h>

namespace vds::enc {

namespace {

using V3 = std::array<double, 3>;
V3 sub(const V3& a, const V3& b) { return {a[0] - b[0], a[1] - b[1], a[2] - b[2]}; }
double dot(const V3& a, const V3& b) { return a[0] * b[0] + a[1] * b[1] + a[2] * b[2]; }
V3 cross(const V3& a, const V3& b) { return {a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]}; }
double len(const V3& a) { return std::sqrt(dot(a, a)); }

uint64_t edge_key(uint32_t a, uint32_t b) { return uint64_t{a} << 32 | b; }

// 2-D points of a region's plane: x along u, y along n x u (a loop that
// runs counter-clockwise about n runs counter-clockwise here).
struct P2 {
  double x, y;
};
double cross2(const P2& o, const P2& a, const P2& b) { return (a.x - o.x) * (b.y - o.y) - (a.y - o.y) * (b.x - o.x); }

// Whether segments p-q and a-b cross at a point inside both.
bool segments_cross(const P2& p, const P2& q, const P2& a, const P2& b) {
  const double d1 = cross2(p, q, a), d2 = cross2(p, q, b), d3 = cross2(a, b, p), d4 = cross2(a, b, q);
  return ((d1 > 1e-9 && d2 < -1e-9) || (d1 < -1e-9 && d2 > 1e-9)) && ((d3 > 1e-9 && d4 < -1e-9) || (d3 < -1e-9 && d4 > 1e-9));
}

// Whether the insides of two counter-clockwise triangles overlap (more than
// by a sliver): no side of either separates them.
bool triangles_overlap(const std::array<P2, 3>& t, const std::array<P2, 3>& u) {
  for (const auto* pr : {&t, &u}) {
    const auto& a = *pr;
    const auto& other = pr == &t ? u : t;
    for (int k = 0; k < 3; ++k) {
      const P2& e0 = a[static_cast<size_t>(k)];
      const P2& e1 = a[static_cast<size_t>((k + 1) % 3)];
      bool all_out = true;
      for (const P2& q : other) all_out = all_out && cross2(e0, e1, q) <= 1e-9;
      if (all_out) return false;
    }
  }
  return true;
}

// Cuts a simple counter-clockwise polygon (loop of welded vertex ids, their
// 2-D points) into triangles ear by ear. false if no ear is found.
bool ear_clip(std::vector<uint32_t> loop, const std::unordered_map<uint32_t, P2>& at, std::vector<std::array<uint32_t, 3>>* out) {
  const auto pt = [&](uint32_t v) { return at.at(v); };
  while (loop.size() > 3) {
    const size_t n = loop.size();
    bool found = false;
    for (size_t i = 0; i < n && !found; ++i) {
      const uint32_t a = loop[(i + n - 1) % n], b = loop[i], c = loop[(i + 1) % n];
      const P2 pa = pt(a), pb = pt(b), pc = pt(c);
      const double area = cross2(pa, pb, pc);
      if (!(area > 1e-9)) continue;  // reflex or flat corner: not an ear
      bool empty = true;
      for (size_t k = 0; k < n && empty; ++k) {
        const uint32_t v = loop[k];
        if (v == a || v == b || v == c) continue;
        const P2 p = pt(v);
        // Inside or on the ear (a point on its edge would leave a sliver).
        if (cross2(pa, pb, p) >= -1e-9 && cross2(pb, pc, p) >= -1e-9 && cross2(pc, pa, p) >= -1e-9) empty = false;
      }
      if (!empty) continue;
      // Nor may an edge of the polygon cross the ear's new side a-c.
      for (size_t k = 0; k < n && empty; ++k) {
        const uint32_t e0 = loop[k], e1 = loop[(k + 1) % n];
        if (e0 == a || e0 == c || e1 == a || e1 == c) continue;
        if (segments_cross(pa, pc, pt(e0), pt(e1))) empty = false;
      }
      if (!empty) continue;
      out->push_back({a, b, c});
      loop.erase(loop.begin() + static_cast<std::ptrdiff_t>(i));
      found = true;
    }
    if (!found) return false;
  }
  if (cross2(pt(loop[0]), pt(loop[1]), pt(loop[2])) <= 1e-9) return false;
  out->push_back({loop[0], loop[1], loop[2]});
  return true;
}

// A scene's vertices welded by position (to 1/64 unit): `rep` maps each
// welded id to the first vertex there, `tri` holds each triangle's corners
// as welded ids.
struct Welded {
  std::vector<uint32_t> rep;
  std::vector<std::array<uint32_t, 3>> tri;
};
Welded weld_positions(const Scene& s) {
  Welded w;
  std::vector<uint32_t> weld(s.vertices.size());
  std::map<std::array<int64_t, 3>, uint32_t> ids;
  for (size_t v = 0; v < s.vertices.size(); ++v) {
    std::array<int64_t, 3> k{};
    for (int a = 0; a < 3; ++a) k[static_cast<size_t>(a)] = std::llround(double{s.vertices[v].pos[static_cast<size_t>(a)]} * 64);
    const auto [it, fresh] = ids.emplace(k, static_cast<uint32_t>(w.rep.size()));
    if (fresh) w.rep.push_back(static_cast<uint32_t>(v));
    weld[v] = it->second;
  }
  w.tri.resize(s.triangles());
  for (size_t t = 0; t < w.tri.size(); ++t)
    for (int c = 0; c < 3; ++c) w.tri[t][static_cast<size_t>(c)] = weld[s.indices[3 * t + static_cast<size_t>(c)]];
  return w;
}

// Each triangle's surface (-1: none holds it).
std::vector<int32_t> surfaces_of(const Scene& s) {
  std::vector<int32_t> of(s.triangles(), -1);
  for (size_t k = 0; k < s.surfaces.size(); ++k)
    for (uint32_t i = 0; i < s.surfaces[k].index_count / 3; ++i) of[s.surfaces[k].first_index / 3 + i] = static_cast<int32_t>(k);
  return of;
}

// A triangle's corners turned (its winding kept) to start at the lowest:
// the same for a triangle with the same corners the same way round.
std::array<uint32_t, 3> lowest_first(std::array<uint32_t, 3> k) {
  while (k[0] > k[1] || k[0] > k[2]) k = {k[1], k[2], k[0]};
  return k;
}

// Whether triangle t of surface sf takes part in merging and decimation:
// opaque and one-sided (sky, fog, additive, alpha-tested and two-sided
// triangles stay as they are).
bool solid(const Scene& s, const SceneSurface& sf) {
  if (sf.kind != SurfaceKind::opaque) return false;
  if (sf.texture >= 0 && static_cast<size_t>(sf.texture) < s.textures.size()) {
    const SceneTexture& tx = s.textures[static_cast<size_t>(sf.texture)];
    if (tx.blend != ShaderBlend::opaque || tx.two_sided) return false;
  }
  return true;
}

// The solid triangles of `s` that are not polygon faces (face_type 1:
// a map's brush faces and the merged regions) decimated within `tolerance`
// scene units (scene_shape.h). Triangles are grouped by which way round their corners
// run about the side their vertex normals face; each group is decimated on
// its own (an edge between the groups is then open, its vertices fixed), so
// that a decimated triangle's winding still tells its front. A triangle the
// decimation leaves as it was stays in its surface with its vertices; the
// others go to a surface of their own per group.
void decimate(Scene* s, double tolerance, ShapeStats* st) {
  const size_t nt = s->triangles();
  const Welded wd = weld_positions(*s);
  const std::vector<uint32_t>& rep = wd.rep;
  const std::vector<std::array<uint32_t, 3>>& tri = wd.tri;
  if (rep.empty()) return;
  std::vector<float> at;  // welded positions, x y z
  for (uint32_t v : rep)
    for (float c : s->vertices[v].pos) at.push_back(c);
  const auto pos = [&](uint32_t w) { return V3{at[3 * w], at[3 * w + 1], at[3 * w + 2]}; };
  const std::vector<int32_t> surface_of = surfaces_of(*s);
  // Each solid triangle's group: 0 where its corners run counter-clockwise
  // about its vertex normals, 1 where they run the other way; -1 not decimated.
  std::vector<int8_t> group(nt, -1);
  std::array<std::vector<uint32_t>, 2> indices;
  for (size_t t = 0; t < nt; ++t) {
    if (surface_of[t] < 0) continue;
    const SceneSurface& sf = s->surfaces[static_cast<size_t>(surface_of[t])];
    if (sf.face_type == 1 || !solid(*s, sf)) continue;
    const auto& w = tri[t];
    if (w[0] == w[1] || w[1] == w[2] || w[0] == w[2]) continue;
    const V3 n = cross(sub(pos(w[1]), pos(w[0])), sub(pos(w[2]), pos(w[0])));
    if (!(len(n) > 1e-9)) continue;
    V3 vn{0, 0, 0};
    for (int c = 0; c < 3; ++c) {
      const auto& q = s->vertices[s->indices[3 * t + static_cast<size_t>(c)]].normal;
      vn = {vn[0] + q[0], vn[1] + q[1], vn[2] + q[2]};
    }
    const int8_t g = dot(n, vn) < 0 ? 1 : 0;
    group[t] = g;
    for (uint32_t v : w) indices[static_cast<size_t>(g)].push_back(v);
  }
  // Triangles as they were, by their corners from the lowest.
  std::map<std::array<uint32_t, 3>, uint32_t> before;
  for (size_t t = 0; t < nt; ++t)
    if (group[t] >= 0) before.emplace(lowest_first(tri[t]), static_cast<uint32_t>(t));
  std::vector<char> stays(nt, 0);
  std::array<std::vector<std::array<uint32_t, 3>>, 2> fresh;
  const float scale = meshopt_simplifyScale(at.data(), rep.size(), 3 * sizeof(float));
  for (size_t g = 0; g < 2; ++g) {
    std::vector<uint32_t>& in = indices[g];
    if (in.empty()) continue;
    std::vector<uint32_t> out(in.size());
    const float err = scale > 0 ? static_cast<float>(tolerance / scale) : 0.0f;
    out.resize(meshopt_simplify(out.data(), in.data(), in.size(), at.data(), rep.size(), 3 * sizeof(float), 0, err,
                                meshopt_SimplifyLockBorder, nullptr));
    st->decimated_in += in.size() / 3;
    st->decimated_out += out.size() / 3;
    for (size_t i = 0; i + 2 < out.size(); i += 3) {
      const std::array<uint32_t, 3> k{out[i], out[i + 1], out[i + 2]};
      // (A triangle on three fixed vertices in a line covers nothing.)
      if (!(len(cross(sub(pos(k[1]), pos(k[0])), sub(pos(k[2]), pos(k[0])))) > 1e-9)) continue;
      const auto it = before.find(lowest_first(k));
      if (it != before.end() && group[it->second] == static_cast<int8_t>(g)) stays[it->second] = 1;
      else fresh[g].push_back(k);
    }
  }
  // The scene again: each surface's triangles but the decimated ones, then
  // each group's new triangles.
  std::vector<uint32_t> old = std::move(s->indices);
  std::vector<SceneSurface> surfaces = std::move(s->surfaces);
  s->indices.clear();
  s->surfaces.clear();
  std::array<int32_t, 2> first_surface{-1, -1};
  for (const SceneSurface& sf : surfaces) {
    SceneSurface k = sf;
    k.first_index = static_cast<uint32_t>(s->indices.size());
    for (uint32_t i = 0; i < sf.index_count / 3; ++i) {
      const size_t t = sf.first_index / 3 + i;
      if (group[t] >= 0) {
        int32_t& f = first_surface[static_cast<size_t>(group[t])];
        if (f < 0) f = static_cast<int32_t>(&sf - surfaces.data());
        if (!stays[t]) continue;
      }
      for (int c = 0; c < 3; ++c) s->indices.push_back(old[3 * t + static_cast<size_t>(c)]);
    }
    k.index_count = static_cast<uint32_t>(s->indices.size()) - k.first_index;
    if (k.index_count > 0) s->surfaces.push_back(k);
  }
  for (size_t g = 0; g < 2; ++g) {
    if (fresh[g].empty()) continue;
    SceneSurface k = surfaces[static_cast<size_t>(first_surface[g])];
    k.first_index = static_cast<uint32_t>(s->indices.size());
    for (const auto& t : fresh[g]) {
      V3 n = cross(sub(pos(t[1]), pos(t[0])), sub(pos(t[2]), pos(t[0])));
      const double l = len(n);
      const double sign = g == 0 ? 1 : -1;
      n = {sign * n[0] / l, sign * n[1] / l, sign * n[2] / l};
      for (uint32_t w : t) {
        SceneVertex v = s->vertices[rep[w]];
        v.normal = {static_cast<float>(n[0]), static_cast<float>(n[1]), static_cast<float>(n[2])};
        s->indices.push_back(static_cast<uint32_t>(s->vertices.size()));
        s->vertices.push_back(v);
      }
    }
    k.index_count = static_cast<uint32_t>(s->indices.size()) - k.first_index;
    s->surfaces.push_back(k);
  }
}

}  // namespace

Scene simplify_shape(const Scene& s, const ShapeOptions& o, ShapeStats* stats) {
  ShapeStats st;
  const size_t nt = s.triangles();
  st.triangles_in = nt;
  // Vertices by position (1/64 unit), the first of each position standing for it.
  const Welded wd = weld_positions(s);
  const std::vector<uint32_t>& rep = wd.rep;  // welded id -> a vertex of the scene
  const std::vector<std::array<uint32_t, 3>>& tri = wd.tri;
  const auto pos = [&](uint32_t w) {
    const auto& p = s.vertices[rep[w]].pos;
    return V3{p[0], p[1], p[2]};
  };
  // Which triangles may join a region, and each one's surface.
  const std::vector<int32_t> surface_of = surfaces_of(s);
  std::vector<V3> normal(nt);
  std::vector<char> joins(nt, 0);
  std::vector<uint32_t> uses(rep.size(), 0);  // triangles using each welded vertex
  for (size_t t = 0; t < nt; ++t) {
    for (uint32_t w : tri[t]) ++uses[w];
    if (surface_of[t] < 0) continue;
    if (!solid(s, s.surfaces[static_cast<size_t>(surface_of[t])])) continue;
    if (tri[t][0] == tri[t][1] || tri[t][1] == tri[t][2] || tri[t][0] == tri[t][2]) continue;
    const V3 nrm = cross(sub(pos(tri[t][1]), pos(tri[t][0])), sub(pos(tri[t][2]), pos(tri[t][0])));
    const double l = len(nrm);
    if (!(l > 1e-6)) continue;
    normal[t] = {nrm[0] / l, nrm[1] / l, nrm[2] / l};
    joins[t] = 1;
  }
  // A joining triangle that repeats another (the same corners the same way
  // round) adds nothing to the shape: it is dropped.
  std::vector<char> repeat(nt, 0);
  {
    std::map<std::array<uint32_t, 3>, uint32_t> seen;
    for (size_t t = 0; t < nt; ++t) {
      if (!joins[t]) continue;
      if (!seen.emplace(lowest_first(tri[t]), static_cast<uint32_t>(t)).second) {
        repeat[t] = 1;
        joins[t] = 0;
        ++st.repeats;
      }
    }
  }
  // Each joining triangle's edges, split at the vertices of the triangles
  // in its plane that lie on them (a face's edge may hold its neighbour's
  // corner: the neighbour's two edges there and the face's one edge then
  // match piece by piece).
  std::vector<std::vector<std::pair<uint32_t, uint32_t>>> pieces(nt);
  {
    std::map<std::array<int64_t, 4>, std::vector<uint32_t>> planes;
    for (size_t t = 0; t < nt; ++t) {
      if (!joins[t]) continue;
      const V3& nm = normal[t];
      planes[{std::llround(nm[0] * 4096), std::llround(nm[1] * 4096), std::llround(nm[2] * 4096),
              std::llround(dot(nm, pos(tri[t][0])) * 16)}]
          .push_back(static_cast<uint32_t>(t));
    }
    std::vector<uint32_t> verts;
    std::vector<std::pair<double, uint32_t>> on;
    for (const auto& [key, members] : planes) {
      verts.clear();
      for (uint32_t t : members)
        for (uint32_t w : tri[t]) verts.push_back(w);
      std::sort(verts.begin(), verts.end());
      verts.erase(std::unique(verts.begin(), verts.end()), verts.end());
      for (uint32_t t : members) {
        for (int c = 0; c < 3; ++c) {
          const uint32_t ea = tri[t][static_cast<size_t>(c)], eb = tri[t][static_cast<size_t>((c + 1) % 3)];
          const V3 pa = pos(ea), d = sub(pos(eb), pa);
          const double l2 = dot(d, d);
          on.clear();
          for (uint32_t v : verts) {
            if (v == ea || v == eb) continue;
            const V3 q = sub(pos(v), pa);
            const double f = dot(q, d) / l2;
            if (!(f > 0 && f < 1)) continue;
            const V3 off = sub(q, V3{d[0] * f, d[1] * f, d[2] * f});
            if (dot(off, off) <= 1.0 / (256.0 * 256.0)) on.emplace_back(f, v);
          }
          std::sort(on.begin(), on.end());
          uint32_t from = ea;
          for (const auto& [f, v] : on) {
            pieces[t].emplace_back(from, v);
            from = v;
          }
          pieces[t].emplace_back(from, eb);
        }
      }
    }
  }
  // The joining triangles by the directed edge pieces they have.
  std::unordered_map<uint64_t, std::vector<uint32_t>> edge;
  edge.reserve(nt * 4);
  for (size_t t = 0; t < nt; ++t)
    for (const auto& [ea, eb] : pieces[t]) edge[edge_key(ea, eb)].push_back(static_cast<uint32_t>(t));
  // Regions: grown from each triangle not yet in one across shared edges.
  std::vector<int32_t> region(nt, -1);
  std::vector<std::vector<uint32_t>> regions;
  for (size_t seed = 0; seed < nt; ++seed) {
    if (!joins[seed] || region[seed] >= 0) continue;
    const int32_t r = static_cast<int32_t>(regions.size());
    regions.emplace_back();
    std::vector<uint32_t>& members = regions.back();
    const V3 n0 = normal[seed];
    const double d0 = dot(n0, pos(tri[seed][0]));
    region[seed] = r;
    members.push_back(static_cast<uint32_t>(seed));
    for (size_t i = 0; i < members.size(); ++i) {
      const uint32_t t = members[i];
      for (const auto& [ea, eb] : pieces[t]) {
        const auto it = edge.find(edge_key(eb, ea));
        if (it == edge.end()) continue;
        for (const uint32_t u : it->second) {
          if (region[u] >= 0 || !joins[u] || dot(normal[u], n0) < 1 - 1e-4) continue;
          bool flat = true;
          for (uint32_t w : tri[u]) flat = flat && std::fabs(dot(n0, pos(w)) - d0) <= o.plane_tolerance;
          if (!flat) continue;
          region[u] = r;
          members.push_back(u);
        }
      }
    }
  }
  // Each region of two or more triangles: its outline, loop by loop.
  struct Outline {
    bool ok = true;
    std::vector<std::vector<uint32_t>> loops;
    std::unordered_map<uint32_t, P2> at;  // its vertices in the plane's 2-D frame
  };
  std::vector<Outline> outlines(regions.size());
  // fixed[v]: v stays wherever it is on an outline (a triangle that keeps
  // its shape uses it, or an outline turns there).
  std::vector<char> fixed(rep.size(), 0);
  for (size_t t = 0; t < nt; ++t)
    if (!repeat[t] && (region[t] < 0 || regions[static_cast<size_t>(region[t])].size() < 2))
      for (uint32_t v : tri[t]) fixed[v] = 1;
  std::vector<std::vector<uint32_t>> regions_at(rep.size());  // regions using each vertex
  for (size_t r = 0; r < regions.size(); ++r) {
    const std::vector<uint32_t>& members = regions[r];
    if (members.size() < 2) continue;
    ++st.regions;
    Outline& ol = outlines[r];
    bool& ok = ol.ok;
    std::unordered_map<uint32_t, uint32_t> next;  // the outline: vertex -> the next
    // The outline: the pieces of the region's triangles that no piece the
    // other way round cancels.
    std::unordered_map<uint64_t, int> count;
    std::vector<uint32_t> used;
    for (uint32_t t : members) {
      for (uint32_t v : tri[t]) used.push_back(v);
      for (const auto& [a, b] : pieces[t]) ++count[edge_key(a, b)];
    }
    for (const auto& [k, c] : count) {
      const uint32_t a = static_cast<uint32_t>(k >> 32), b = static_cast<uint32_t>(k);
      const auto back = count.find(edge_key(b, a));
      const int left = c - (back == count.end() ? 0 : back->second);
      if (left <= 0) continue;
      if (left > 1 || !next.emplace(a, b).second) ok = false;  // the outline touches itself at a
      used.push_back(a);
    }
    std::sort(used.begin(), used.end());
    used.erase(std::unique(used.begin(), used.end()), used.end());
    for (uint32_t v : used) regions_at[v].push_back(static_cast<uint32_t>(r));
    // Loops of the outline.
    std::vector<std::vector<uint32_t>>& loops = ol.loops;
    if (ok) {
      // (From the lowest vertex of each, so that the result does not
      // depend on the order of a hash table.)
      std::vector<uint32_t> starts;
      for (const auto& [v, unused] : next) starts.push_back(v);
      std::sort(starts.begin(), starts.end());
      std::unordered_map<uint32_t, char> seen;
      for (const uint32_t start : starts) {
        if (seen.count(start)) continue;
        std::vector<uint32_t> loop;
        uint32_t v = start;
        while (!seen.count(v)) {
          seen[v] = 1;
          loop.push_back(v);
          const auto it = next.find(v);
          if (it == next.end()) {
            ok = false;
            break;
          }
          v = it->second;
        }
        if (!ok || v != start) {
          ok = false;
          break;
        }
        loops.push_back(std::move(loop));
      }
    }
    // The plane's 2-D frame.
    const V3 n = normal[members[0]];
    V3 u = std::fabs(n[0]) < 0.9 ? cross(n, V3{1, 0, 0}) : cross(n, V3{0, 1, 0});
    u = {u[0] / len(u), u[1] / len(u), u[2] / len(u)};
    const V3 w = cross(n, u);
    for (uint32_t v : used) {
      const V3 p = pos(v);
      ol.at[v] = {dot(p, u), dot(p, w)};
    }
    // Where an outline turns, its vertex stays (for every region that has it).
    for (const auto& loop : loops) {
      const size_t m = loop.size();
      for (size_t i = 0; i < m; ++i) {
        const V3 pa = pos(loop[(i + m - 1) % m]), pb = pos(loop[i]), pc = pos(loop[(i + 1) % m]);
        const V3 ac = sub(pc, pa);
        const double l = len(ac);
        if (!(l > 0) || len(cross(ac, sub(pb, pa))) / l > 1.0 / 256 || dot(sub(pb, pa), sub(pc, pb)) <= 0) fixed[loop[i]] = 1;
      }
    }
  }
  // Each region drawn as its outline with the vertices that are not fixed
  // dropped; a region that cannot be (or gains nothing) keeps its
  // triangles, which fixes their vertices: the regions sharing them are
  // cut again, until nothing changes.
  std::vector<std::vector<std::array<uint32_t, 3>>> drawn(regions.size());  // welded ids; empty: keeps its triangles
  std::vector<char> keeps(regions.size(), 0), dirty(regions.size(), 0);
  std::vector<uint32_t> work;
  for (size_t r = 0; r < regions.size(); ++r)
    if (regions[r].size() >= 2) {
      work.push_back(static_cast<uint32_t>(r));
      dirty[r] = 1;
    }
  for (size_t wi = 0; wi < work.size(); ++wi) {
    const uint32_t r = work[wi];
    dirty[r] = 0;
    if (keeps[r]) continue;
    const std::vector<uint32_t>& members = regions[r];
    Outline& ol = outlines[r];
    std::unordered_map<uint32_t, P2>& at = ol.at;
    bool ok = ol.ok;
    std::vector<std::vector<uint32_t>> loops;
    for (const auto& l : ol.loops) {
      std::vector<uint32_t> kept_l;
      for (uint32_t v : l)
        if (fixed[v]) kept_l.push_back(v);
      if (kept_l.size() < 3) ok = false;
      loops.push_back(std::move(kept_l));
    }
    // One outer loop (counter-clockwise) and its holes (clockwise), each
    // hole joined to the outline by a cut from its rightmost vertex to a
    // vertex of the outline it sees.
    std::vector<uint32_t> outline;
    if (ok) {
      const auto area = [&](const std::vector<uint32_t>& l) {
        double a = 0;
        for (size_t i = 0; i < l.size(); ++i) {
          const P2 p = at[l[i]], q = at[l[(i + 1) % l.size()]];
          a += p.x * q.y - q.x * p.y;
        }
        return a / 2;
      };
      std::vector<std::vector<uint32_t>> holes;
      for (auto& l : loops) {
        if (area(l) > 0) {
          if (!outline.empty()) ok = false;  // two outer loops: the region is not one polygon
          outline = l;
        } else {
          holes.push_back(l);
        }
      }
      if (outline.empty()) ok = false;
      // Rightmost holes first.
      const auto right = [&](const std::vector<uint32_t>& l) {
        size_t best = 0;
        for (size_t i = 1; i < l.size(); ++i)
          if (at[l[i]].x > at[l[best]].x) best = i;
        return best;
      };
      std::sort(holes.begin(), holes.end(),
                [&](const std::vector<uint32_t>& a, const std::vector<uint32_t>& b) { return at[a[right(a)]].x > at[b[right(b)]].x; });
      for (const auto& h : holes) {
        if (!ok) break;
        const size_t hi = right(h);
        const P2 m = at[h[hi]];
        // The nearest outline vertex to the right of m that no outline edge
        // hides from it (a vertex, so that the cut ends on the outline).
        double best = 1e300;
        size_t bj = outline.size();
        for (size_t j = 0; j < outline.size(); ++j) {
          const P2 p = at[outline[j]];
          if (p.x < m.x) continue;
          const double d = (p.x - m.x) * (p.x - m.x) + (p.y - m.y) * (p.y - m.y);
          if (d >= best) continue;
          // No edge of `l` but those ending at `end` crosses m-p.
          const auto clear_of = [&](const std::vector<uint32_t>& l, uint32_t end) {
            for (size_t e = 0; e < l.size(); ++e) {
              const uint32_t ea = l[e], eb = l[(e + 1) % l.size()];
              if (ea == end || eb == end) continue;
              const P2 a = at[ea], b = at[eb];
              const double d1 = cross2(m, p, a), d2 = cross2(m, p, b), d3 = cross2(a, b, m), d4 = cross2(a, b, p);
              if (((d1 > 0) != (d2 > 0)) && ((d3 > 0) != (d4 > 0))) return false;
            }
            return true;
          };
          if (clear_of(outline, outline[j]) && clear_of(h, h[hi])) {
            best = d;
            bj = j;
          }
        }
        if (bj == outline.size()) {
          ok = false;
          break;
        }
        // outline[..bj], hole from hi round to hi, outline[bj..].
        std::vector<uint32_t> joined(outline.begin(), outline.begin() + static_cast<std::ptrdiff_t>(bj) + 1);
        for (size_t k = 0; k <= h.size(); ++k) joined.push_back(h[(hi + k) % h.size()]);
        joined.insert(joined.end(), outline.begin() + static_cast<std::ptrdiff_t>(bj), outline.end());
        outline = std::move(joined);
      }
    }
    std::vector<std::array<uint32_t, 3>> cut;
    ok = ok && outline.size() >= 3 && ear_clip(outline, at, &cut) && cut.size() < members.size();
    if (ok) {
      // The cut covers what the triangles covered (no more: a cut that went
      // outside the outline or overlapped itself would show).
      double before = 0, after = 0;
      for (uint32_t t : members) before += cross2(at[tri[t][0]], at[tri[t][1]], at[tri[t][2]]) / 2;
      for (const auto& t : cut) after += cross2(at[t[0]], at[t[1]], at[t[2]]) / 2;
      ok = std::fabs(after - before) <= 1e-6 * std::max(1.0, before);
      // and no two of its triangles overlap: with the same area, nothing
      // is left uncovered either.
      std::vector<std::array<P2, 3>> flat;
      for (const auto& t : cut) flat.push_back({at[t[0]], at[t[1]], at[t[2]]});
      for (size_t i = 0; i < flat.size() && ok; ++i)
        for (size_t j = i + 1; j < flat.size() && ok; ++j) ok = !triangles_overlap(flat[i], flat[j]);
      // and it stays inside the region (points inside each of its
      // triangles lie in one of the region's).
      for (size_t i = 0; i < flat.size() && ok; ++i) {
        const auto& f = flat[i];
        const P2 c{(f[0].x + f[1].x + f[2].x) / 3, (f[0].y + f[1].y + f[2].y) / 3};
        for (int k = 0; k < 4 && ok; ++k) {
          const P2 q = k == 3 ? c : P2{(c.x + f[static_cast<size_t>(k)].x) / 2, (c.y + f[static_cast<size_t>(k)].y) / 2};
          bool inside = false;
          for (uint32_t t : members) {
            const P2 a = at[tri[t][0]], b = at[tri[t][1]], d = at[tri[t][2]];
            inside = inside || (cross2(a, b, q) >= -1e-9 && cross2(b, d, q) >= -1e-9 && cross2(d, a, q) >= -1e-9);
            if (inside) break;
          }
          ok = inside;
        }
      }
    }
    if (ok) {
      drawn[r] = std::move(cut);
      continue;
    }
    keeps[r] = 1;
    drawn[r].clear();
    for (uint32_t t : members)
      for (uint32_t v : tri[t]) {
        if (fixed[v]) continue;
        fixed[v] = 1;
        for (uint32_t q : regions_at[v])
          if (!keeps[q] && !dirty[q]) {
            dirty[q] = 1;
            work.push_back(q);
          }
      }
  }
  for (size_t r = 0; r < regions.size(); ++r) {
    if (regions[r].size() < 2) continue;
    if (keeps[r]) ++st.kept;
    else ++st.merged;
  }
  // The scene again: each surface's triangles outside merged regions, then
  // each merged region as a surface of its own.
  Scene out = s;
  out.indices.clear();
  out.surfaces.clear();
  for (const SceneSurface& sf : s.surfaces) {
    SceneSurface k = sf;
    k.first_index = static_cast<uint32_t>(out.indices.size());
    for (uint32_t i = 0; i < sf.index_count / 3; ++i) {
      const size_t t = sf.first_index / 3 + i;
      if (repeat[t] || (region[t] >= 0 && !drawn[static_cast<size_t>(region[t])].empty())) continue;
      for (int c = 0; c < 3; ++c) out.indices.push_back(s.indices[3 * t + static_cast<size_t>(c)]);
    }
    k.index_count = static_cast<uint32_t>(out.indices.size()) - k.first_index;
    if (k.index_count > 0) out.surfaces.push_back(k);
  }
  for (size_t r = 0; r < regions.size(); ++r) {
    if (drawn[r].empty()) continue;
    SceneSurface k = s.surfaces[static_cast<size_t>(surface_of[regions[r][0]])];
    k.face_type = 1;
    k.first_index = static_cast<uint32_t>(out.indices.size());
    // Vertices of its own, whose normals are the region's (a renderer may
    // tell the front from them: a vertex shared with another surface has
    // that surface's).
    std::unordered_map<uint32_t, uint32_t> own;
    // (Pointing the way the normals of the region's own vertices point:
    // a map's triangles may wind either way round them.)
    V3 n = normal[regions[r][0]];
    double facing = 0;
    for (uint32_t t : regions[r])
      for (int c = 0; c < 3; ++c) {
        const auto& vn = s.vertices[s.indices[3 * t + static_cast<size_t>(c)]].normal;
        facing += dot(n, V3{vn[0], vn[1], vn[2]});
      }
    if (facing < 0) n = {-n[0], -n[1], -n[2]};
    for (const auto& t : drawn[r])
      for (uint32_t wv : t) {
        const auto [it, fresh] = own.emplace(wv, static_cast<uint32_t>(out.vertices.size()));
        if (fresh) {
          SceneVertex v = s.vertices[rep[wv]];
          v.normal = {static_cast<float>(n[0]), static_cast<float>(n[1]), static_cast<float>(n[2])};
          out.vertices.push_back(v);
        }
        out.indices.push_back(it->second);
      }
    k.index_count = static_cast<uint32_t>(out.indices.size()) - k.first_index;
    out.surfaces.push_back(k);
  }
  if (o.tolerance > 0) decimate(&out, o.tolerance, &st);
  st.triangles_out = out.triangles();
  if (stats) *stats = st;
  return out;
}

}  // namespace vds::enc
