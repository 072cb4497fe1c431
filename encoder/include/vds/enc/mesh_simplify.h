// vds encoder: the progressive simplification of Qin, Liu, Bao and Peng,
// "Progressive geometry compression of meshes" (Journal of Software, 2002),
// section 2: half-edge collapses grouped into levels whose removed vertices
// form an independent set, so that the vertex splits of one level commute
// and can be sent sorted by split vertex.
//
//  - vertex priority  α·min_edge(v) + β·max_edge(v), smallest first (eq. 1);
//  - v collapses onto the neighbour u_k with the smallest cone volume
//    |Σ_j ((u_j − u_k) × (u_{j+1} − u_k)) · (v − u_k)| (eqs. 2–4), the next
//    smallest if that collapse is not allowed;
//  - a collapse is allowed only if it keeps the mesh a manifold (link
//    condition, boundary rules, no vertex left with too few faces), turns no
//    face over, keeps every vertex degree within max_degree, and keeps the
//    distance from the original vertices to the simplified surface within
//    the current threshold E_k (the original vertices are carried along on
//    the faces they project to, as in the paper's "distance from the vertices
//    of the original model to the simplified model");
//  - within a level, the 1-ring of a removed vertex is locked (the removed
//    vertices form an independent set) and a vertex takes at most one
//    collapse (so each split vertex splits once per level); vertices are
//    visited by priority rank (0..1) plus packing_weight per still unlocked
//    neighbour, kept up to date as rings get locked: a vertex whose
//    neighbours are mostly locked already costs the level least, so a
//    positive weight packs larger independent sets (a departure from the
//    paper, which visits by priority alone);
//  - thresholds E_k = kE/S, k = 1..S (S from eq. 6 unless given): a level
//    ends once it has removed at least R·|M_{i+1}| vertices; below that the
//    threshold is raised and the level continues. Once k = S (the whole
//    budget E in force) a level that cannot reach R is still kept, and
//    simplification goes on while levels remove at least tail_removal_ratio
//    of the vertices, or anything at all while the mesh is still above
//    target_base_ratio of the input: at coarse levels the independence and
//    manifold constraints, not the error, are what limits a level (a
//    departure from the paper, which stops there; it keeps bases near 1 %).
// Positions are the quantised integer grid: collapses never move a vertex,
// so every level is a sub-mesh of the quantised original.
#pragma once
#include <array>
#include <cstddef>
#include <cstdint>
#include <vector>

namespace vds::enc {

struct SimplifyOptions {
  double alpha = 1.0;          // weight of the shortest edge in the priority (paper: 1.0)
  double beta = 0.01;          // weight of the longest edge (paper: 0.01)
  double rate_weight = 0;      // weight of the prediction residual |v - centroid(ring)| (0: the paper's priority)
  bool area_centroid = false;  // the residual from the ring's area centroid (the area predictor's base point)
  double packing_weight = 0;   // visiting order: priority rank + this per unlocked neighbour (0: by priority)
  double removal_ratio = 0.2;  // R: minimum fraction of a level's vertices removed (paper: 1/5..1/4)
  double max_error = 0.1;      // E as a fraction of the bounding-box diagonal
  double tail_removal_ratio = 0.05;  // levels after E is exhausted go on while they remove this much
  int steps = 0;               // S; 0 = eq. 6 with target_base_ratio
  double target_base_ratio = 0.01;  // for eq. 6 and the stopping rule above
  int max_levels = 0;          // stop after this many levels; 0 = no limit
  int max_degree = 24;         // no vertex of any level gets a higher degree
  size_t min_base_vertices = 4;  // stop once the mesh is this small
};

// One half-edge collapse v -> u of a level, in terms of the finer mesh
// M_{i+1}: around v counter-clockwise, `wing_f` follows u and `wing_l`
// precedes it. A boundary edge (u, v) has one wing: wing_l = -1 when u is
// the first vertex of v's boundary fan, wing_f = -1 when it is the last.
struct Collapse {
  uint32_t v = 0;
  uint32_t u = 0;
  int64_t wing_f = -1;
  int64_t wing_l = -1;
};

struct SimplifyLevel {
  std::vector<Collapse> collapses;  // in the order they were made
  size_t vertices_before = 0;       // |M_{i+1}|
  double threshold = 0;             // E_k in force when the level ended, grid units
  double max_distance = 0;          // largest original-vertex distance at the end of the level, grid units
};

struct SimplifyResult {
  // levels[0] removes vertices from the original mesh; the last level leads
  // to the base mesh. The decoder applies them in reverse.
  std::vector<SimplifyLevel> levels;
  std::vector<uint32_t> base_vertices;                   // original vertex ids, ascending
  std::vector<std::array<uint32_t, 3>> base_triangles;   // original vertex ids
  int steps = 0;                                         // S used
  double error_limit = 0;                                // E in grid units
  int max_degree_seen = 0;                               // over all levels
};

// Simplifies a repaired (manifold, see check_manifold) mesh given on the
// integer grid. Throws std::invalid_argument if the mesh is not manifold.
SimplifyResult simplify_progressive(const std::vector<std::array<int32_t, 3>>& positions,
                                    const std::vector<std::array<uint32_t, 3>>& triangles,
                                    const SimplifyOptions& options);

// Squared distance from point p to triangle (a, b, c) (Ericson, "Real-Time
// Collision Detection", 5.1.5); exact for degenerate triangles too.
double point_triangle_distance2(const std::array<double, 3>& p, const std::array<double, 3>& a,
                                const std::array<double, 3>& b, const std::array<double, 3>& c);

}  // namespace vds::enc
