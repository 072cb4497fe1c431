// `vds encode-mesh IN -o OUT.vds`: a mesh file (OBJ, PLY, glTF, 3DS, Draco
// .drc, ...) as a progressive model-mode stream: import and repair (the
// report says what changed), the independent-set simplification and the
// level-by-level coding of vds/enc/mesh_encoder.h, then the per-level table.
#include <cstdio>
#include <memory>
#include <stdexcept>
#include <string>

#include "commands.h"
#include "vds/enc/mesh_encoder.h"
#include "vds/enc/mesh_import.h"
#include "vds/enc/stream_writer.h"

namespace vds::cli {
namespace {

struct EncodeMeshOptions {
  std::string input;
  std::string output;
  int bits = 10;
  int levels = 0;
  std::string coder = "arith";
  std::string predictor = "area";
  std::string up = "+y";
  bool paper = false;
  double max_error = -1;
  double removal_ratio = -1;
  double rate_weight = -1;
  double packing_weight = -1;
  int steps = 0;
  uint32_t max_chunk = 4096;
  double tail = -1;  // not given: enc::kMeshDefaultTail with the arithmetic coder
  bool quiet = false;
};

void run_encode_mesh(const EncodeMeshOptions& o) {
  enc::MeshEncodeOptions e = o.paper ? enc::paper_mesh_options() : enc::MeshEncodeOptions{};
  e.bits = o.bits;
  if (!o.paper) {
    if (o.coder == "arith")
      e.coder = MeshCoder::arith;
    else if (o.coder == "huffman")
      e.coder = MeshCoder::huffman;
    else
      throw Failure(kExitUsage, "--coder must be arith or huffman, not '" + o.coder + "'");
    if (o.predictor == "parallelogram")
      e.predictor = MeshPredictor::parallelogram;
    else if (o.predictor == "area")
      e.predictor = MeshPredictor::area;
    else if (o.predictor == "laplacian")
      e.predictor = MeshPredictor::laplacian;
    else
      throw Failure(kExitUsage, "--predictor must be area, parallelogram or laplacian, not '" + o.predictor + "'");
  }
  if (!enc::mesh_up_from_name(o.up, &e.up))
    throw Failure(kExitUsage, "--up must be +y, +z, +x, -y, -z or -x (or y, z, x), not '" + o.up + "'");
  if (o.levels > 0) e.simplify.max_levels = o.levels;
  if (o.max_error > 0) e.simplify.max_error = o.max_error;
  if (o.removal_ratio > 0) e.simplify.removal_ratio = o.removal_ratio;
  if (o.rate_weight >= 0) e.simplify.rate_weight = o.rate_weight;
  if (o.packing_weight >= 0) e.simplify.packing_weight = o.packing_weight;
  if (o.steps > 0) e.simplify.steps = o.steps;
  e.max_chunk_payload = o.max_chunk;
  // The paper's coding has no tail; the default tail goes with the default coder.
  const bool arith = !o.paper && e.coder == MeshCoder::arith;
  e.tail_fraction = o.tail >= 0 ? o.tail : (arith ? enc::kMeshDefaultTail : 0);
  if (e.tail_fraction > 0 && !arith)
    throw Failure(kExitUsage, "--tail needs the arithmetic coder: add --tail 0 for --paper or --coder huffman");

  enc::MeshRepairReport report;
  enc::Mesh mesh;
  try {
    mesh = enc::import_mesh(o.input, &report);
  } catch (const std::runtime_error& err) {
    throw Failure(kExitBadInput, err.what());
  }
  enc::MeshEncodeResult r;
  try {
    r = enc::encode_mesh(mesh, e);
  } catch (const std::invalid_argument& err) {
    throw Failure(kExitBadInput, o.input + ": " + err.what());
  }
  enc::write_file(o.output, r.stream);
  if (o.quiet) return;
  std::printf("%s", report.summary().c_str());
  std::printf("%s: %zu bytes, %u-bit grid, %s coder, %s predictor, base %u vertices (%.2f %%), %zu levels, up %s\n",
              o.output.c_str(), r.stream.size(), e.bits, e.coder == MeshCoder::arith ? "arithmetic" : "Huffman",
              vds::enc::mesh_predictor_name(e.predictor), r.mesh_header.base_vertices,
              100.0 * r.mesh_header.base_vertices / r.mesh_header.vertices, r.levels.size() - 1,
              enc::mesh_up_name(e.up));
  if (!r.tail_note.empty()) std::printf("%s\n", r.tail_note.c_str());
  std::printf("%s", enc::format_mesh_table(r.levels, r.stream.size()).c_str());
  const double nv = r.mesh_header.vertices;
  std::printf("bits/vertex: split flags %.2f, arc %.2f, rotation %.2f, positions %.2f, base %.2f\n",
              r.bits.split_flags / nv, r.bits.split_shape / nv, r.bits.split_rotation / nv, r.bits.geometry / nv,
              r.bits.base / nv);
  if (r.tail)
    std::printf("bits/vertex of the single-rate tail (level %zu): connectivity %.2f, positions %.2f; "
                "%u holes closed, at most %u border edges\n",
                r.levels.size() - 1, r.bits.tail_connectivity / nv, r.bits.tail_geometry / nv,
                r.tail_counts.dummy_vertices, r.tail_counts.max_border);
  std::printf("client: %u B workspace + %u B chunk buffer (%.1f B per vertex)\n", r.stream_header.workspace_bytes,
              r.stream_header.max_chunk_payload,
              double(r.stream_header.workspace_bytes + r.stream_header.max_chunk_payload) / nv);
}

}  // namespace

void add_encode_mesh(CLI::App& app) {
  auto o = std::make_shared<EncodeMeshOptions>();
  CLI::App* sub =
      app.add_subcommand("encode-mesh", "Encode a mesh file as a progressive model stream (levels of vertex splits)");
  sub->add_option("IN", o->input, "Mesh file: OBJ, PLY, glTF 2.0, GLB, 3DS, Collada, IQM, MD2, MD3, MS3D (assimp) or Draco .drc")->required();
  sub->add_option("-o,--output", o->output, "Stream to write")->required();
  sub->add_option("--bits", o->bits, "Quantisation bits per axis")->capture_default_str()->check(CLI::Range(2, 16));
  sub->add_option("--levels", o->levels, "At most this many refinement levels (0: as many as the error allows)")
      ->check(CLI::NonNegativeNumber);
  sub->add_option("--coder", o->coder, "arith (context-adaptive arithmetic) or huffman (the paper's)")
      ->capture_default_str();
  sub->add_option("--predictor", o->predictor, "area (the ring's area centroid) or parallelogram (its vertex centroid), moved toward the parallelogram predictions by a per-level weight; or laplacian (the paper's eq. 13)")
      ->capture_default_str();
  sub->add_option("--up", o->up,
                  "The model's up axis, for viewers: +y (default, as glTF), +z (common in CAD and scans), +x, -y, -z "
                  "or -x; stored in the stream, positions unchanged")
      ->capture_default_str();
  sub->add_flag("--paper", o->paper,
                "The paper's choices throughout: Huffman, Laplacian predictor, priority of eq. 1 only");
  sub->add_option("--max-error", o->max_error, "Simplification error budget E, fraction of the bounding-box diagonal")
      ->check(CLI::Range(1e-6, 10.0));
  sub->add_option("--removal-ratio", o->removal_ratio, "R: least fraction of vertices a level removes")
      ->check(CLI::Range(0.01, 0.5));
  sub->add_option("--rate-weight", o->rate_weight, "Weight of the prediction residual in the removal priority")
      ->check(CLI::Range(0.0, 1000.0));
  sub->add_option("--packing-weight", o->packing_weight,
                  "Removal order: priority rank plus this per neighbour a removal locks (0: priority only)")
      ->check(CLI::Range(0.0, 1000.0));
  sub->add_option("--steps", o->steps, "S: threshold steps (0: from eq. 6)")->check(CLI::NonNegativeNumber);
  sub->add_option("--max-chunk", o->max_chunk, "Largest chunk payload, bytes (the client's chunk buffer)")
      ->capture_default_str()->check(CLI::Range(512u, 1u << 24));
  sub->add_option("--tail", o->tail,
                  "Send the whole mesh single-rate as the last level, after the split levels that reach this "
                  "fraction of the vertices (default 0.04 with the arithmetic coder; 0: splits all the way)")
      ->check(CLI::Range(0.0, 1.0));
  sub->add_flag("-q,--quiet", o->quiet, "Print nothing");
  sub->callback([o] { run_encode_mesh(*o); });
}

}  // namespace vds::cli
