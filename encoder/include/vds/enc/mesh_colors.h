// vds encoder: textured models and their mesh colors (docs/model-mode.md).
//
// Import: a UV-textured model through assimp (glTF 2.0, OBJ+MTL, 3DS,
// MD2/MD3, Collada, IQM, MS3D, ...): triangulated, node transforms applied,
// every mesh merged; positions welded when bit-identical (so the UV seams
// of the file vanish: mesh colors need no map) and faces left with a
// repeated vertex dropped. Each face keeps its corners' texture coordinates,
// its material (texture, colour) and its corners' vertex colours.
//
// Conversion to mesh colors (the rule):
//  - a face's resolution R = 2^r is the smallest power of two with
//    R >= density * sqrt(2 * A), A the face's area in texels of its
//    texture (a lattice of resolution R has about R^2 / 2 samples), capped
//    at max_res_log2; a face without a texture gets the samples per unit
//    of surface of the textured faces around its vertices (so a colour
//    change at a window in a painted body is as sharp as the texture
//    beside it), or where untextured faces of different colours meet and
//    no textured face is near, the model's median textured density; else
//    R = 1 (vertex samples only); faces on a seam of the map whose two
//    sides' colours differ (by more than 24 levels, on average along it)
//    get twice their resolution;
//  - a sample's colour is the texture's, filtered to the sample spacing
//    (trilinear on a box-filtered pyramid, coordinates repeating), times
//    the material colour and the barycentric blend of the corners' vertex
//    colours; a face without a texture has that product alone;
//  - an edge sample is the mean of what each face on the edge samples
//    there (through its own texture coordinates), a vertex sample the mean
//    over the faces around it: a seam of the map is averaged, not kept;
//  - MIP level m samples the texture again at resolution R / 2^m (the
//    vertex samples are level 0's at every level).
#pragma once
#include <array>
#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

#include "vds/enc/image_io.h"

namespace vds::enc {

struct TexturedMaterial {
  int texture = -1;                          // into TexturedModel::textures, -1 for none
  std::array<double, 3> colour{1, 1, 1};     // linear factor on the texture (0..1)
};

struct TexturedModel {
  std::string name;
  std::vector<std::array<double, 3>> positions;   // welded
  std::vector<std::array<uint32_t, 3>> triangles;
  std::vector<std::array<std::array<double, 2>, 3>> uv;       // per face corner; v up (OpenGL)
  std::vector<std::array<std::array<double, 3>, 3>> colour;   // per face corner vertex colour (0..1)
  std::vector<int> material;                                  // per face
  std::vector<TexturedMaterial> materials;
  std::vector<Image> textures;                                // RGB
  std::vector<std::string> texture_files;
  size_t dropped_faces = 0;  // faces with a repeated vertex after welding
};

// Loads a model file (the rule above). Texture images are read from the
// model's folder or below it (PNG, JPEG, TGA, BMP, PNM) or from the file
// itself (GLB). A folder holding lower.md3, upper.md3 and head.md3 is a
// Quake III player: its three parts joined at their tags (frame 0); so is
// "ARCHIVE.pk3:FOLDER", the player's folder read from inside a .pk3.
// Throws std::runtime_error naming the file, what is wrong and where.
TexturedModel load_textured_model(const std::string& path);
// The same for a file's bytes held in memory; `name`'s extension says the
// format; no other file may be opened (only textures the file holds are read).
TexturedModel read_textured_model(const uint8_t* data, size_t size, const std::string& name);

struct MeshColorsOptions {
  double density = 1.0;   // samples per texel side
  int max_res_log2 = 10;  // R <= 1024
  int min_res_log2 = 0;   // for textured faces
  bool seam_boost = true;  // faces on a seam whose sides' colours differ get twice the resolution
  // Optional, one per face: the largest exponent each face may have (after
  // the rules above), e.g. what a display can show of it.
  std::vector<uint8_t> face_max_res;
  // Optional, one per face: the exponent whose sample spacing filters the
  // face's part of its corners' vertex samples (default: its own), so that
  // faces made coarser (rd_face_resolutions) keep their vertex samples.
  std::vector<uint8_t> vertex_filter_res;
};

// A model's mesh colors on the host.
struct MeshColorsModel {
  std::vector<std::array<double, 3>> positions;
  std::vector<uint16_t> triangles;   // 3 per face
  std::vector<uint8_t> face_res;     // r per face
  int max_res = 0;
  std::vector<uint8_t> vertex_ycc;   // 3 per vertex
  // Per MIP level 0 .. max_res (the last: vertices only), the Y', Cb, Cr
  // planes in the client's layout (vds/mesh_colors.h).
  std::vector<std::array<std::vector<uint8_t>, 3>> levels;
  uint32_t samples(int m) const { return static_cast<uint32_t>(levels[m][0].size()); }
};

// The vds encoder's sample density for quality factor q: one sample per
// texel side at q <= 0.25, then fewer as q grows (0.5 / sqrt(q), at least
// 0.25): as a video encoder lowers the resolution at low rates, a coarser
// lattice coded finely beats a fine one coded coarsely.
double density_for_quality(double quality);

// Converts (the rule above). Throws std::runtime_error for a model beyond
// the client's limits (65,535 vertices, vds::mc::kMaxFaces faces).
MeshColorsModel to_mesh_colors(const TexturedModel& model, const MeshColorsOptions& o = MeshColorsOptions{});

// The weight of an error in Y', Cb, Cr as it weighs in R'G'B' (the sum of
// the squares of its column of the JFIF inverse: 3, 3.26, 2.48), as a
// fraction: a luma-equivalent squared error.
constexpr double kComponentWeight[3] = {3.0 / 8.74, 3.26 / 8.74, 2.48 / 8.74};

// Per face of `mc` and per k = 0 .. its exponent r: the squared error
// (kComponentWeight) over the face's own level-0 samples when level k's
// lattice predicts them, each by the linear filter at its point (k = 0: 0).
std::vector<std::vector<double>> coarser_face_sse(const MeshColorsModel& mc);

// JFIF full-range R'G'B' -> Y'CbCr of one colour, rounded (Taskin eq. 2.3).
std::array<uint8_t, 3> rgb_to_ycc(double r, double g, double b);

// --- The codec ---------------------------------------------------------------
struct MccEncoded {
  std::vector<uint8_t> header;  // MCLH payload
  // MCLV payloads: per level (0 .. max_res - 1), its chunks in order.
  std::vector<std::vector<std::vector<uint8_t>>> levels;
  // The bytes of level m's chunks (0 for the last level, vertex samples only).
  size_t level_bytes(int m) const {
    size_t n = 0;
    if (m >= 0 && static_cast<size_t>(m) < levels.size())
      for (const auto& c : levels[static_cast<size_t>(m)]) n += c.size();
    return n;
  }
};

struct MccOptions {
  // The thesis's codec (its transform scaling, run/amplitude pairs), or the
  // vds mode: the orthonormal transform (the tables' steps mean what they
  // mean in JPEG), DC predicted from the reconstructed means of the blocks
  // around, AC coded as a count, significance and levels in contexts by
  // position (the image codec's scheme, docs/texture-codec.md).
  bool paper = false;
  // vds mode: AC levels rounded down below 0.5 + deadzone of a step.
  double deadzone = 0.2;
  // The largest MCLV payload (a client's chunk buffer); 0: a level in one chunk.
  size_t max_chunk = 0;
  // The vertex samples travel with the vertices (MCVX), not in MCLH
  // (vds::mc::kFlagVertexColours).
  bool vertex_colours_outside = false;
  // Each level's chroma coded from the next level's samples, on its lattice
  // (vds::mc::kFlagChromaHalf; Taskin section 2.3, chroma from MIP level 1):
  // about a quarter of the chroma samples (choose_colours measures whether
  // it pays).
  bool chroma_half = false;
  // vds mode, vertex samples in MCLH: their differences from the
  // predictions are coded in multiples of this step (vds::mc::kFlagVertexStep;
  // 1: lossless; 0: vertex_step_for_quality).
  int vertex_step = 0;
};

// The vds encoder's vertex sample step at quality factor q (MccOptions::
// vertex_step): the vertex samples are lossy as the blocks' means are.
int vertex_step_for_quality(double quality);
// `mc` with its vertex samples as a client reconstructs them from
// differences coded in steps of `step` (what the vds mode codes the levels
// from; step 1: mc itself).
MeshColorsModel with_stepped_vertex_samples(const MeshColorsModel& mc, int step);


// Every level of `mc` at quality factor `quality` (the JPEG tables'
// multiplier, 1/256 .. 255).
MccEncoded encode_mesh_colors(const MeshColorsModel& mc, double quality, const MccOptions& o = MccOptions{});

// Decodes `enc` through the client library (vds::mc::MeshColors): the
// planes of level m, as a client shows them.
std::array<std::vector<uint8_t>, 3> decode_mesh_colors_level(const MeshColorsModel& mc, const MccEncoded& enc, int m);

// The choice of face resolutions at quality factor q: level 0 coded as `o`
// codes it gives the squared error D of each face's own samples; a face
// takes the coarsest lattice, k levels down, whose prediction of those
// samples (coarser_face_sse) plus its own coding error (about D 4^-k) is no
// more than D: its bits fall about 4^k-fold and its error does not grow.
// Returns each face's exponent (at most its own). The error is counted
// where the samples lie, not on a display, which averages coding noise
// more than lost detail; so a face is made coarser only where that costs
// nothing, not traded against its bits.
std::vector<uint8_t> rd_face_resolutions(const MeshColorsModel& mc, double quality, const MccOptions& o);
// to_mesh_colors, then again with rd_face_resolutions' exponents as the
// faces' caps (the vertex samples kept); the second from `fine`, the first
// already made.
MeshColorsModel to_mesh_colors_rd(const TexturedModel& model, const MeshColorsOptions& mo, double quality,
                                  const MccOptions& o);
MeshColorsModel to_mesh_colors_rd(const TexturedModel& model, const MeshColorsOptions& mo, const MeshColorsModel& fine,
                                  double quality, const MccOptions& o);

}  // namespace vds::enc
