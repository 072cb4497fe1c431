// vds encoder: triangle meshes on the host — import (OBJ, PLY, glTF 2.0,
// 3DS and the other formats of assimp; Draco .drc through libdraco), the
// repair that turns any triangle soup into the oriented 2-manifold with
// boundary the progressive codec needs, quantisation, and PLY/OBJ export.
//
// The repair rule (docs/mesh-codec.md, "Import and repair"), in order:
//  1. vertices with a non-finite coordinate are dropped with their faces;
//  2. vertices at bit-identical positions are welded (0.0 and -0.0 equal);
//  3. faces with a repeated vertex after welding (degenerate) are dropped;
//  4. faces over the same three vertices as an earlier face, in either
//     orientation (duplicates), are dropped — the first one is kept;
//  5. an edge is *shared* when exactly two faces use it in opposite
//     directions; every other edge (three or more faces: non-manifold; two
//     faces in the same direction: orientation conflict) is cut open, i.e.
//     treated as boundary on every face that uses it;
//  6. each vertex gets one copy per fan of faces connected through shared
//     edges around it (non-manifold vertices are split; copies keep the
//     position); steps 5–6 repeat until nothing changes;
//  7. if a cut edge still has more than two faces, or two faces in the same
//     direction, because every face around it stayed in one fan, the later
//     faces on it are dropped and steps 5–7 repeat;
//  8. vertices no face uses are dropped.
// Face orientation is never changed and no face is ever added. Every change
// is counted in a MeshRepairReport.
#pragma once
#include <array>
#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

namespace vds::enc {

// An indexed triangle mesh on the host, positions in model units.
struct Mesh {
  std::vector<std::array<double, 3>> positions;
  std::vector<std::array<uint32_t, 3>> triangles;  // counter-clockwise seen from outside
};

// What the import and the repair changed, each counted once.
struct MeshRepairReport {
  size_t input_vertices = 0;             // as the file (or caller) gave them
  size_t input_faces = 0;                // triangles after the importer's triangulation
  size_t non_triangle_primitives = 0;    // points and lines the file held, dropped
  size_t non_finite_vertices = 0;        // step 1
  size_t faces_with_non_finite = 0;      // step 1
  size_t welded_vertices = 0;            // step 2: vertices merged into an earlier one
  size_t degenerate_faces = 0;           // step 3
  size_t duplicate_faces = 0;            // step 4
  size_t non_manifold_edges = 0;         // step 5: edges with three or more faces (first pass)
  size_t orientation_conflicts = 0;      // step 5: edges with two same-direction faces (first pass)
  size_t split_vertices = 0;             // step 6: vertex copies added
  size_t dropped_faces = 0;              // step 7
  size_t unreferenced_vertices = 0;      // step 8
  size_t output_vertices = 0;
  size_t output_faces = 0;
  size_t boundary_edges = 0;             // in the result
  size_t components = 0;                 // connected components of the result

  // True if anything other than welding changed the mesh.
  bool repaired() const;
  // One line per non-zero count, e.g. "welded 174163 vertices at identical positions".
  std::string summary() const;
};

// Loads a mesh file. Draco (`.drc`, or bytes starting "DRACO") goes through
// libdraco, everything else through assimp (its data-structure validation
// first, then triangulated, node transforms applied, all meshes of the
// scene merged); a PLY file is checked by the project's own reader first
// (declared counts against the file's size, list lengths, vertex indices).
// The importer may open only files in the model's folder (glTF buffers).
// Only positions and faces are kept. The result is NOT yet repaired: call
// repair_mesh(). Throws std::runtime_error naming the file, what is wrong
// and where, if it cannot be read or holds no triangles.
Mesh load_mesh_file(const std::string& path, MeshRepairReport* report = nullptr);
// The same for a file's bytes held in memory; `name`'s extension says the
// format where the bytes do not (.obj, .gltf, .glb, ...); no other file may
// be opened.
Mesh load_mesh_bytes(const uint8_t* data, size_t size, const std::string& name, MeshRepairReport* report = nullptr);

// Decodes a Draco mesh held in memory (libdraco): positions and faces.
// Throws std::runtime_error with `what` in the message if it is not one.
Mesh decode_draco(const uint8_t* data, size_t size, const std::string& what);

// Encodes positions and faces with libdraco (quantisation bits `qp`,
// compression level `cl`), as `draco_encoder -qp qp -cl cl` does.
std::vector<uint8_t> encode_draco(const Mesh& m, int qp, int cl);

// Applies the repair rule above. Never throws on any input (indices out of
// range are counted as faces with a non-finite vertex and dropped).
Mesh repair_mesh(const Mesh& in, MeshRepairReport* report = nullptr);

// load_mesh_file followed by repair_mesh, sharing one report.
Mesh import_mesh(const std::string& path, MeshRepairReport* report = nullptr);

// The manifold checks the codec relies on: every edge has one face, or two
// in opposite directions; every vertex has exactly one fan; no degenerate or
// duplicate face; no unreferenced vertex. Returns "" if they hold, else a
// description of the first violation.
std::string check_manifold(const Mesh& m);

// Axis-aligned bounds and diagonal.
struct Bounds {
  std::array<double, 3> min{};
  std::array<double, 3> max{};
  double diagonal() const;
  double max_extent() const;
};
Bounds mesh_bounds(const Mesh& m);

// Uniform quantisation on a cube grid: q = round((p - origin) / step), with
// step = max_extent / (2^bits - 1) so the largest extent spans the whole
// range, as Draco quantises (same grid for the same bits).
struct Quantisation {
  int bits = 0;
  std::array<double, 3> origin{};
  double step = 1;
  std::array<double, 3> to_model(const std::array<int32_t, 3>& q) const;
};
Quantisation make_quantisation(const Bounds& b, int bits);
std::vector<std::array<int32_t, 3>> quantise(const Mesh& m, const Quantisation& q);

// Writers for tools and benchmarks (ASCII PLY / OBJ, positions and faces).
void write_ply(const std::string& path, const Mesh& m);
void write_obj(const std::string& path, const Mesh& m);

}  // namespace vds::enc
