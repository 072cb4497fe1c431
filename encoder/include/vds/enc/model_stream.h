// vds encoder: a textured model as one model-mode stream — the progressive
// mesh (vds/enc/mesh_encoder.h), then its colour as mesh colors
// (vds/enc/mesh_colors.h): MCLH once the mesh is whole, then the MIP
// levels coarsest first, each in chunks a client's chunk buffer holds
// (docs/model-mode.md, "The model stream").
//
// The colours are keyed to the mesh as the client decodes it: the encoder
// decodes its own geometry with the client library and converts the model
// in that vertex and face order, so vertex v and face f of MCLH are the
// client's vertex v and triangle f.
#pragma once
#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

#include "vds/enc/mesh_colors.h"
#include "vds/enc/mesh_encoder.h"
#include "vds/enc/mesh_import.h"

namespace vds::enc {

struct ModelStreamOptions {
  // The geometry: a 10-bit grid (a client's display shows far less), split
  // levels up to 30 % of the vertices before the single-rate tail, so the
  // coarse mesh arriving with its vertex colours is recognisable early
  // (the duck at 2 KB/s: 25 dB after 1.5 s, against 4.8 s with vds
  // encode-mesh's 4 %).
  ModelStreamOptions() {
    mesh.bits = 10;
    mesh.tail_fraction = 0.3;
    colors.max_res_log2 = 8;
  }
  MeshEncodeOptions mesh;     // geometry (grid bits, up axis, frame size, chunk size)
  MeshColorsOptions colors;   // conversion; its density is set from the quality unless fixed_density
  bool fixed_density = false;
  MccOptions codec;           // mesh colors codec (max_chunk: the mesh's max_chunk_payload)
  // vds codec: chroma lattice and face resolutions chosen by looking
  // (choose_colours, from 4 orbit views of the client's frame size);
  // false: codec.chroma_half as given, and faces made coarser where that
  // costs nothing in their samples (rd_face_resolutions) if coarser_faces.
  bool measure_colours = true;
  bool coarser_faces = false;
  double quality = 1;         // the codec's quality factor (JPEG tables' multiplier)
  // > 0: the finest quality (of a ladder from 1/8 to 64) whose whole stream
  // takes at most this many bytes; the quality above is then ignored.
  size_t max_bytes = 0;
  // > 0 (and no max_bytes): the coarsest quality of that ladder whose
  // finest picture, as the rate schedule measures it, reaches this PSNR.
  double min_psnr = 0;
  // Vertex colours with their vertices (MCVX after the base and each split
  // level), so the coarse mesh is drawn in colour.
  bool vertex_colours = true;
  // Samples per client pixel side a face may have, seen as near as the
  // client's model view ever sees it (its orbit at 3.2 units from the
  // centre, the model within its bounding sphere, a focal length of the
  // frame height): a face's R at most the power of two at or above
  // samples_per_pixel x sqrt(2 x its area in pixels) (0: no cap).
  double samples_per_pixel = 1;
  // The rate schedule: geometry with its vertex colours, then the vertex
  // samples (MCLH), then the MIP levels coarsest first — each only if, as
  // the client shows it from this many orbit angles, it is better than the
  // best coarser one (0: every level is sent).
  int schedule_views = 4;
  // The orbit script at the end (MORB chunks): a turn of the finished model
  // in this many frames (0: none).
  uint32_t orbit_frames = 0;
};

// Where the stream's bytes go (chunk framing included).
struct ModelStreamParts {
  size_t geometry = 0;             // preamble, HEAD, mesh chunks, END
  size_t vertex_colours = 0;       // MCVX chunks' bytes
  size_t vertex_chunks = 0;        // and their number
  size_t orbit = 0;                // MORB chunks
  size_t colors_header = 0;        // MCLH
  std::vector<size_t> level_bytes; // MCLV chunks per level (0 the finest)
  std::vector<size_t> level_end;   // stream offset where each level's last chunk ends
  size_t geometry_end = 0;         // stream offset after the mesh's last chunk
  size_t colors_header_end = 0;    // after MCLH
};

struct ModelStreamResult {
  std::vector<uint8_t> stream;
  StreamHeader header{};      // its HEAD
  double quality = 0;
  MeshRepairReport repair;
  MeshEncodeResult mesh;      // the geometry alone (its own stream)
  TexturedModel decoded;      // the model in the client's vertex and face order
  MeshColorsModel colors;     // its mesh colors (uncoded)
  MccEncoded coded;           // and coded
  std::vector<bool> sent;     // per level: in the stream (the rate schedule)
  std::vector<double> level_psnr;  // per level (max_res: vertex samples) as the schedule measured it
  uint32_t orbit_frames = 0;       // MORB's
  ModelStreamParts parts;
};

// Encodes `model` (load_textured_model). Throws std::invalid_argument for a
// model the codecs cannot take (not made manifold by the repair, above the
// client's limits) or a byte budget no quality meets.
ModelStreamResult encode_model_stream(const TexturedModel& model, const ModelStreamOptions& o);

// --- The stream as a viewer sees it arrive ------------------------------------
// After every chunk that completes a client frame, the client's picture —
// its mesh and the colours it holds, drawn by the client library's model
// view — from `views` orbit angles, against the reference at the same
// cameras: the model through its UV map with its own textures (double,
// supersampled). PSNR over the pixels inside the reference's silhouette
// (its coverage eroded by a pixel, so anti-aliased edges count for neither).
struct TimelineOptions {
  int views = 8;
  int supersample = 3;
  bool colours_only = false;  // only the frames from MCLH on
  // When set: each view's reference and client picture of the last frame
  // measured (DIR/view<k>_reference.png, DIR/view<k>_<label>.png).
  std::string images_dir;
  std::string label = "vds";
};
struct TimelinePoint {
  size_t bytes = 0;          // stream bytes received when the frame is drawn
  uint32_t vertices = 0;     // of the client's mesh
  int colour_level = -1;     // the mesh colors level shown (-1: none, max_res: vertex samples)
  double psnr = 0;
};
std::vector<TimelinePoint> model_timeline(const TexturedModel& model, const ModelStreamResult& r,
                                          const TimelineOptions& o = TimelineOptions{});

// The same measure of the model with `textures` in place of its own, on its
// own geometry, at the cameras of the whole mesh, drawn as a client draws a
// textured mesh (the client library's renderer, RGB565, bilinear): what a
// download of the model with its texture coded by another codec shows once
// it is complete. With the model's own textures: the client renderer's
// ceiling.
double model_views_psnr(const TexturedModel& model, const std::vector<Image>& textures, const ModelStreamResult& r,
                        const TimelineOptions& o = TimelineOptions{});

}  // namespace vds::enc
