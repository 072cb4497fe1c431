// vds encoder: the mesh repair rule of vds/enc/mesh_import.h — weld, drop
// degenerate and duplicate faces, cut non-manifold edges and split
// non-manifold vertices into one copy per fan (the "cutting" half of
// Guéziec, Taubin, Lazarus and Horn, "Cutting and stitching", IEEE TVCG 2001).
#include <algorithm>
#include <cmath>
#include <cstring>
#include <numeric>
#include <string>

#include "vds/enc/mesh_import.h"

namespace vds::enc {
namespace {

using Tri = std::array<uint32_t, 3>;

uint64_t edge_key(uint32_t a, uint32_t b) {
  return a < b ? (uint64_t{a} << 32 | b) : (uint64_t{b} << 32 | a);
}

struct UnionFind {
  std::vector<uint32_t> parent;
  explicit UnionFind(size_t n) : parent(n) { std::iota(parent.begin(), parent.end(), 0u); }
  uint32_t find(uint32_t x) {
    while (parent[x] != x) {
      parent[x] = parent[parent[x]];
      x = parent[x];
    }
    return x;
  }
  void unite(uint32_t a, uint32_t b) {
    a = find(a);
    b = find(b);
    if (a == b) return;
    if (a < b) std::swap(a, b);
    parent[a] = b;  // the smaller index is the root: deterministic roots
  }
};

// Half-edges grouped by undirected edge: entry = (key, corner), corner =
// 3 * face + k for the edge from tri[k] to tri[(k + 1) % 3].
struct EdgeGroups {
  std::vector<std::pair<uint64_t, uint32_t>> half;  // sorted by key, then corner
  std::vector<size_t> start;                        // group g = half[start[g], start[g+1])

  explicit EdgeGroups(const std::vector<Tri>& tris) {
    half.reserve(tris.size() * 3);
    for (uint32_t f = 0; f < tris.size(); ++f)
      for (uint32_t k = 0; k < 3; ++k) half.emplace_back(edge_key(tris[f][k], tris[f][(k + 1) % 3]), 3 * f + k);
    std::sort(half.begin(), half.end());
    for (size_t i = 0; i < half.size(); ++i)
      if (i == 0 || half[i].first != half[i - 1].first) start.push_back(i);
    start.push_back(half.size());
  }
  size_t groups() const { return start.size() - 1; }
};

uint32_t edge_from(const std::vector<Tri>& t, uint32_t c) { return t[c / 3][c % 3]; }

// Two half-edges of one undirected edge run in opposite directions.
bool opposite(const std::vector<Tri>& t, uint32_t c1, uint32_t c2) {
  return edge_from(t, c1) != edge_from(t, c2);
}

// The neighbour across each half-edge (corner), or -1, under the "shared"
// rule: exactly two half-edges, opposite directions.
std::vector<int64_t> shared_neighbours(const std::vector<Tri>& tris, const EdgeGroups& eg, size_t* non_manifold,
                                       size_t* conflicts) {
  std::vector<int64_t> across(tris.size() * 3, -1);
  for (size_t g = 0; g < eg.groups(); ++g) {
    const size_t n = eg.start[g + 1] - eg.start[g];
    if (n == 2) {
      const uint32_t c1 = eg.half[eg.start[g]].second, c2 = eg.half[eg.start[g] + 1].second;
      if (opposite(tris, c1, c2)) {
        across[c1] = c2;
        across[c2] = c1;
      } else if (conflicts) {
        ++*conflicts;
      }
    } else if (n > 2 && non_manifold) {
      ++*non_manifold;
    }
  }
  return across;
}

// Splits every vertex into one copy per fan. Returns the number of copies.
size_t split_fans(std::vector<Tri>& tris, std::vector<std::array<double, 3>>& pos,
                  const std::vector<int64_t>& across) {
  const size_t nc = tris.size() * 3;
  UnionFind uf(nc);
  // Corner c = 3f + k sits at vertex tri[k]. Its two edges are half-edge k
  // (tri[k] -> tri[k+1]) and half-edge k+2 (tri[k+2] -> tri[k]). Across a
  // shared half-edge, the same vertex is at the far end of the twin.
  for (uint32_t c = 0; c < nc; ++c) {
    const uint32_t f = c / 3, k = c % 3;
    const int64_t tw = across[c];  // half-edge k: tri[k] -> tri[k+1]; twin runs tri[k+1] -> tri[k]
    if (tw >= 0) {
      const uint32_t tf = static_cast<uint32_t>(tw) / 3, tk = static_cast<uint32_t>(tw) % 3;
      uf.unite(c, 3 * tf + (tk + 1) % 3);  // the twin's end is our vertex
    }
    const uint32_t hp = 3 * f + (k + 2) % 3;  // half-edge tri[k+2] -> tri[k]
    const int64_t tw2 = across[hp];
    if (tw2 >= 0) {
      const uint32_t tf = static_cast<uint32_t>(tw2) / 3, tk = static_cast<uint32_t>(tw2) % 3;
      uf.unite(c, 3 * tf + tk);  // the twin starts at our vertex
    }
  }
  // First fan (lowest corner) keeps the vertex; each further fan gets a copy.
  std::vector<int64_t> first_root(pos.size(), -1);
  std::vector<std::pair<uint32_t, uint32_t>> extra;  // (root, new vertex)
  size_t copies = 0;
  std::vector<uint32_t> remap(nc);
  for (uint32_t c = 0; c < nc; ++c) {
    const uint32_t v = tris[c / 3][c % 3];
    const uint32_t r = uf.find(c);
    if (first_root[v] < 0) first_root[v] = r;
    remap[c] = v;
    if (static_cast<uint32_t>(first_root[v]) == r) continue;
    // Roots are the smallest corner of their fan, so the copy for a fan is
    // created when its root corner is reached.
    if (r == c) {
      pos.push_back(pos[v]);
      extra.emplace_back(r, static_cast<uint32_t>(pos.size() - 1));
      ++copies;
    }
  }
  if (copies == 0) return 0;
  std::sort(extra.begin(), extra.end());
  for (uint32_t c = 0; c < nc; ++c) {
    const uint32_t v = tris[c / 3][c % 3];
    const uint32_t r = uf.find(c);
    if (static_cast<uint32_t>(first_root[v]) == r) continue;
    const auto it = std::lower_bound(extra.begin(), extra.end(), std::make_pair(r, 0u));
    tris[c / 3][c % 3] = it->second;
  }
  return copies;
}

// Drops faces so that no edge keeps more than two faces or a same-direction
// pair: keeps the first opposite pair (or the first face). Returns the count.
size_t drop_excess_faces(std::vector<Tri>& tris) {
  const EdgeGroups eg(tris);
  std::vector<char> drop(tris.size(), 0);
  for (size_t g = 0; g < eg.groups(); ++g) {
    const size_t b = eg.start[g], e = eg.start[g + 1];
    if (e - b < 2) continue;
    if (e - b == 2 && opposite(tris, eg.half[b].second, eg.half[b + 1].second)) continue;
    // Keep the first face and the first later face running the other way.
    const uint32_t keep1 = eg.half[b].second;
    int64_t keep2 = -1;
    for (size_t i = b + 1; i < e; ++i)
      if (!drop[eg.half[i].second / 3] && opposite(tris, keep1, eg.half[i].second)) {
        keep2 = eg.half[i].second;
        break;
      }
    for (size_t i = b + 1; i < e; ++i) {
      const uint32_t c = eg.half[i].second;
      if (static_cast<int64_t>(c) != keep2 && c / 3 != keep1 / 3) drop[c / 3] = 1;
    }
  }
  size_t dropped = 0;
  std::vector<Tri> kept;
  kept.reserve(tris.size());
  for (size_t f = 0; f < tris.size(); ++f) {
    if (drop[f])
      ++dropped;
    else
      kept.push_back(tris[f]);
  }
  tris.swap(kept);
  return dropped;
}

}  // namespace

bool MeshRepairReport::repaired() const {
  return non_triangle_primitives || non_finite_vertices || faces_with_non_finite || degenerate_faces ||
         duplicate_faces || non_manifold_edges || orientation_conflicts || split_vertices || dropped_faces ||
         unreferenced_vertices;
}

std::string MeshRepairReport::summary() const {
  std::string s;
  auto line = [&s](size_t n, const char* what) {
    if (n) s += std::to_string(n) + " " + what + "\n";
  };
  s += "input: " + std::to_string(input_vertices) + " vertices, " + std::to_string(input_faces) + " triangles\n";
  line(non_triangle_primitives, "point/line primitives dropped");
  line(non_finite_vertices, "vertices with a non-finite coordinate dropped");
  line(faces_with_non_finite, "faces on dropped or out-of-range vertices dropped");
  line(welded_vertices, "vertices welded into an earlier one at the identical position");
  line(degenerate_faces, "degenerate faces (repeated vertex) dropped");
  line(duplicate_faces, "duplicate faces (same three vertices) dropped");
  line(non_manifold_edges, "non-manifold edges (3+ faces) cut open");
  line(orientation_conflicts, "edges with two same-direction faces cut open");
  line(split_vertices, "vertex copies made to split non-manifold vertices");
  line(dropped_faces, "faces dropped on edges that could not be cut apart");
  line(unreferenced_vertices, "unreferenced vertices dropped");
  s += "output: " + std::to_string(output_vertices) + " vertices, " + std::to_string(output_faces) + " triangles, " +
       std::to_string(boundary_edges) + " boundary edges, " + std::to_string(components) + " component" +
       (components == 1 ? "" : "s") + "\n";
  return s;
}

Mesh repair_mesh(const Mesh& in, MeshRepairReport* report) {
  MeshRepairReport local;
  MeshRepairReport& r = report ? *report : local;
  if (r.input_vertices == 0 && r.input_faces == 0) {
    r.input_vertices = in.positions.size();
    r.input_faces = in.triangles.size();
  }
  const size_t nv = in.positions.size();

  // 1. Non-finite vertices.
  std::vector<char> bad(nv, 0);
  for (size_t i = 0; i < nv; ++i)
    for (int k = 0; k < 3; ++k)
      if (!std::isfinite(in.positions[i][k])) bad[i] = 1;
  r.non_finite_vertices = static_cast<size_t>(std::count(bad.begin(), bad.end(), 1));

  // 2. Weld bit-identical positions (-0.0 counts as 0.0): sort, then map
  // every vertex to the first of its run in input order.
  std::vector<uint32_t> order;
  order.reserve(nv);
  for (uint32_t i = 0; i < nv; ++i)
    if (!bad[i]) order.push_back(i);
  auto key = [&in](uint32_t i) {
    std::array<double, 3> p = in.positions[i];
    for (double& c : p)
      if (c == 0) c = 0;  // -0.0 -> +0.0
    return p;
  };
  std::stable_sort(order.begin(), order.end(), [&](uint32_t a, uint32_t b) { return key(a) < key(b); });
  std::vector<int64_t> weld(nv, -1);
  for (size_t i = 0; i < order.size(); ++i) {
    if (i > 0 && key(order[i]) == key(order[i - 1]))
      weld[order[i]] = weld[order[i - 1]];
    else
      weld[order[i]] = order[i];
  }
  // Runs were sorted stably, so each run's first element has the lowest index.
  for (uint32_t i : order)
    if (weld[i] != i) ++r.welded_vertices;

  // 1 (faces), 3 and 4: faces on dropped vertices, degenerate, duplicate.
  std::vector<Tri> tris;
  tris.reserve(in.triangles.size());
  std::vector<std::array<uint32_t, 4>> seen;  // sorted vertices + face index
  for (const Tri& t0 : in.triangles) {
    bool ok = true;
    Tri t{};
    for (int k = 0; k < 3; ++k) {
      if (t0[k] >= nv || bad[t0[k]]) {
        ok = false;
        break;
      }
      t[k] = static_cast<uint32_t>(weld[t0[k]]);
    }
    if (!ok) {
      ++r.faces_with_non_finite;
      continue;
    }
    if (t[0] == t[1] || t[1] == t[2] || t[0] == t[2]) {
      ++r.degenerate_faces;
      continue;
    }
    tris.push_back(t);
  }
  {
    std::vector<std::array<uint32_t, 4>> keys(tris.size());
    for (uint32_t f = 0; f < tris.size(); ++f) {
      Tri s = tris[f];
      std::sort(s.begin(), s.end());
      keys[f] = {s[0], s[1], s[2], f};
    }
    std::sort(keys.begin(), keys.end());
    std::vector<char> dup(tris.size(), 0);
    for (size_t i = 1; i < keys.size(); ++i)
      if (keys[i][0] == keys[i - 1][0] && keys[i][1] == keys[i - 1][1] && keys[i][2] == keys[i - 1][2])
        dup[keys[i][3]] = 1;  // sorted by face index within a run: the first stays
    std::vector<Tri> kept;
    kept.reserve(tris.size());
    for (size_t f = 0; f < tris.size(); ++f) {
      if (dup[f])
        ++r.duplicate_faces;
      else
        kept.push_back(tris[f]);
    }
    tris.swap(kept);
  }

  // 5-7. Cut, split, drop until stable.
  std::vector<std::array<double, 3>> pos = in.positions;
  bool first_pass = true;
  for (int round = 0; round < 1000; ++round) {
    const EdgeGroups eg(tris);
    const std::vector<int64_t> across = shared_neighbours(tris, eg, first_pass ? &r.non_manifold_edges : nullptr,
                                                          first_pass ? &r.orientation_conflicts : nullptr);
    first_pass = false;
    const size_t copies = split_fans(tris, pos, across);
    r.split_vertices += copies;
    if (copies) continue;
    const size_t dropped = drop_excess_faces(tris);
    r.dropped_faces += dropped;
    if (!dropped) break;
  }

  // 8. Compact: keep referenced vertices in order of first index.
  std::vector<int64_t> remap(pos.size(), -1);
  for (const Tri& t : tris)
    for (uint32_t v : t) remap[v] = 0;
  Mesh out;
  for (size_t i = 0; i < pos.size(); ++i) {
    if (remap[i] < 0) {
      if (i < nv && !bad[i] && weld[i] == static_cast<int64_t>(i)) ++r.unreferenced_vertices;
      continue;
    }
    remap[i] = static_cast<int64_t>(out.positions.size());
    out.positions.push_back(pos[i]);
  }
  out.triangles.reserve(tris.size());
  for (const Tri& t : tris)
    out.triangles.push_back(
        {static_cast<uint32_t>(remap[t[0]]), static_cast<uint32_t>(remap[t[1]]), static_cast<uint32_t>(remap[t[2]])});

  r.output_vertices = out.positions.size();
  r.output_faces = out.triangles.size();
  {
    const EdgeGroups eg(out.triangles);
    r.boundary_edges = 0;
    for (size_t g = 0; g < eg.groups(); ++g)
      if (eg.start[g + 1] - eg.start[g] == 1) ++r.boundary_edges;
    UnionFind uf(out.positions.size());
    for (const Tri& t : out.triangles) {
      uf.unite(t[0], t[1]);
      uf.unite(t[1], t[2]);
    }
    r.components = 0;
    for (uint32_t i = 0; i < out.positions.size(); ++i)
      if (uf.find(i) == i) ++r.components;
  }
  return out;
}

std::string check_manifold(const Mesh& m) {
  const std::vector<Tri>& tris = m.triangles;
  const size_t nv = m.positions.size();
  std::vector<char> used(nv, 0);
  for (size_t f = 0; f < tris.size(); ++f) {
    const Tri& t = tris[f];
    for (uint32_t v : t) {
      if (v >= nv) return "face " + std::to_string(f) + " uses vertex " + std::to_string(v) + " out of range";
      used[v] = 1;
    }
    if (t[0] == t[1] || t[1] == t[2] || t[0] == t[2]) return "face " + std::to_string(f) + " is degenerate";
  }
  for (size_t v = 0; v < nv; ++v)
    if (!used[v]) return "vertex " + std::to_string(v) + " is unreferenced";
  const EdgeGroups eg(tris);
  for (size_t g = 0; g < eg.groups(); ++g) {
    const size_t n = eg.start[g + 1] - eg.start[g];
    const uint64_t k = eg.half[eg.start[g]].first;
    const std::string name = "edge (" + std::to_string(k >> 32) + ", " + std::to_string(k & 0xFFFFFFFFu) + ")";
    if (n > 2) return name + " has " + std::to_string(n) + " faces";
    if (n == 2 && !opposite(tris, eg.half[eg.start[g]].second, eg.half[eg.start[g] + 1].second))
      return name + " has two faces in the same direction";
  }
  {
    std::vector<std::array<uint32_t, 3>> keys(tris.size());
    for (size_t f = 0; f < tris.size(); ++f) {
      keys[f] = tris[f];
      std::sort(keys[f].begin(), keys[f].end());
    }
    std::sort(keys.begin(), keys.end());
    for (size_t i = 1; i < keys.size(); ++i)
      if (keys[i] == keys[i - 1]) return "two faces share the same three vertices";
  }
  std::vector<Tri> copy = tris;
  std::vector<std::array<double, 3>> pos = m.positions;
  const std::vector<int64_t> across = shared_neighbours(copy, eg, nullptr, nullptr);
  if (split_fans(copy, pos, across) != 0) return "a vertex has more than one fan of faces";
  return "";
}

}  // namespace vds::enc
