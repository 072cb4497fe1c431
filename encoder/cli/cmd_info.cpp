// `vds info FILE`: header fields, budgets and the chunk list of a stream,
// read with the client's own parser so the answer is what a client sees.
#include <cinttypes>
#include <cstdio>
#include <cstring>
#include <memory>
#include <string>
#include <vector>

#include "commands.h"
#include "vds/bytes.h"
#include "vds/container.h"
#include "vds/image.h"
#include "vds/terrain_client.h"
#include "vds/walk.h"
#include "vds/jpeg.h"
#include "vds/enc/mesh_encoder.h"
#include "vds/enc/scene.h"
#include "vds/enc/stream_writer.h"

namespace vds::cli {
namespace {

struct InfoOptions {
  std::string file;
  uint64_t workspace = 64u << 20;
  uint32_t chunk_buffer = 1u << 24;
  bool summary = false;
};

struct ChunkRow {
  uint64_t offset;
  uint32_t type;
  uint32_t size;
  std::string note;
};

struct Collector {
  StreamParser* parser = nullptr;
  std::vector<ChunkRow> rows;
  std::vector<std::string> meta;
  enc::MeshChunkSummary mesh;  // progressive mesh chunks: the per-level table
};

const char* mode_name(StreamMode m) {
  switch (m) {
    case StreamMode::images: return "images";
    case StreamMode::walkthrough: return "walkthrough";
    case StreamMode::terrain: return "terrain";
    case StreamMode::model: return "model";
  }
  return "?";
}

std::string q16(int32_t v) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "%.4f", static_cast<double>(v) / 65536.0);
  return buf;
}

// `vds info SCENE`: what a walkthrough would stream of a map.
void run_scene_info(const InfoOptions& o) {
  const enc::Scene s = enc::load_scene(o.file);
  size_t lightmapped = 0, sky = 0, fog = 0, additive = 0, found = 0, scripted = 0;
  uint64_t texture_bytes = 0;
  for (const enc::SceneSurface& f : s.surfaces) {
    if (f.lightmap >= 0) lightmapped += f.index_count / 3;
    if (f.kind == enc::SurfaceKind::sky) sky += f.index_count / 3;
    if (f.kind == enc::SurfaceKind::fog) fog += f.index_count / 3;
    if (f.kind == enc::SurfaceKind::additive) additive += f.index_count / 3;
  }
  std::vector<bool> used(s.textures.size(), false);
  for (const enc::SceneSurface& f : s.surfaces) used[static_cast<size_t>(f.texture)] = true;
  size_t used_count = 0;
  std::vector<std::string> missing;
  for (size_t t = 0; t < s.textures.size(); ++t) {
    if (!used[t]) continue;
    ++used_count;
    scripted += s.textures[t].scripted;
    if (!s.textures[t].file.empty()) {
      ++found;
      texture_bytes += s.textures[t].bytes;
    } else {
      missing.push_back(s.textures[t].name);
    }
  }
  std::printf("%s: %s\n", s.name.c_str(), s.kind.c_str());
  std::printf("  faces              %u polygons, %u patches, %u meshes, %u billboards (dropped); %u skipped (nodraw, hint, skip, or no model)\n",
              s.polygons, s.patches, s.meshes, s.billboards, s.skipped);
  std::printf("  triangles          %zu (%zu lightmapped, %zu sky, %zu in fog, %zu additive), %zu vertices, %zu surfaces\n",
              s.triangles(), lightmapped, sky, fog, additive, s.vertices.size(), s.surfaces.size());
  std::printf("  bounds             (%.0f %.0f %.0f) .. (%.0f %.0f %.0f) map units\n", s.min[0], s.min[1], s.min[2], s.max[0],
              s.max[1], s.max[2]);
  std::printf("  textures           %zu used (%zu by shader scripts), %zu found, %" PRIu64 " bytes in their files\n", used_count,
              scripted, found, texture_bytes);
  for (const std::string& m : missing) std::printf("    missing          %s\n", m.c_str());
  std::printf("  lightmaps          %zu of %dx%d (%zu bytes)\n", s.lightmaps.size(), enc::kLightmapSide, enc::kLightmapSide,
              s.lightmaps.size() * enc::kLightmapSide * enc::kLightmapSide * 3);
  std::printf("  spawn points       %zu\n", s.spawns.size());
  for (const enc::SpawnPoint& p : s.spawns)
    std::printf("    %-22s (%.0f %.0f %.0f) yaw %.0f\n", p.classname.c_str(), p.origin[0], p.origin[1], p.origin[2], p.yaw_deg);
}

// A vds stream starts with its magic; anything else is taken for a scene.
bool is_stream(const std::string& file) {
  std::FILE* f = std::fopen(file.c_str(), "rb");
  if (f == nullptr) return false;
  uint8_t magic[sizeof kStreamMagic] = {};
  const size_t n = std::fread(magic, 1, sizeof magic, f);
  std::fclose(f);
  return n == sizeof magic && std::memcmp(magic, kStreamMagic, sizeof magic) == 0;
}

void run_info(const InfoOptions& o) {
  const std::string ext = o.file.size() > 4 ? o.file.substr(o.file.size() - 4) : "";
  if (!is_stream(o.file) && (ext == ".bsp" || ext == ".BSP" || o.file.find_first_of("./") == std::string::npos)) {
    run_scene_info(o);
    return;
  }
  const std::vector<uint8_t> bytes = enc::read_file(o.file);
  if (o.chunk_buffer < kHeaderPayloadMax) throw Failure(kExitUsage, "--chunk-buffer must be at least 256");
  if (o.workspace < o.chunk_buffer) throw Failure(kExitUsage, "--workspace must hold the chunk buffer");
  // Untouched beyond the chunk buffer: the parser only measures what is left.
  std::unique_ptr<uint8_t[]> memory(new uint8_t[o.workspace]);
  Arena arena(memory.get(), o.workspace);

  Collector col;
  StreamParser parser;
  col.parser = &parser;
  ChunkSink sink;
  sink.ctx = &col;
  sink.on_chunk = [](void* ctx, uint32_t type, const uint8_t* payload, uint32_t size) {
    auto* c = static_cast<Collector*>(ctx);
    const uint64_t end = c->parser->bytes_consumed();
    ChunkRow row{end - kChunkHeadBytes - size - kChunkTailBytes, type, size, ""};
    if (type == chunk::kMeta) {
      c->meta.emplace_back(reinterpret_cast<const char*>(payload), size);
      row.note = "metadata";
      c->rows.push_back(row);
      return ChunkResult::consumed;
    }
    if (c->mesh.add(type, payload, size)) {
      row.note = "progressive mesh";
      c->rows.push_back(row);
      return ChunkResult::consumed;
    }
    if (type == chunk::kImageHeader) {
      ImageHeader ih;
      if (image_header_from_bytes(payload, size, &ih) == Status::ok) {
        const char* chroma = ih.chroma == ChromaFormat::yuv420 ? "4:2:0" : ih.chroma == ChromaFormat::yuv444 ? "4:4:4" : "grey";
        row.note = "vds image header: " + std::to_string(ih.width) + "x" + std::to_string(ih.height) + " " + chroma +
                   ", quantisers " + std::to_string(ih.quant_luma) + "/" + std::to_string(ih.quant_chroma) +
                   (ih.residual() ? ", residual" : "") + (ih.region() ? ", region" : "");
      } else {
        row.note = "vds image header (malformed)";
      }
      c->rows.push_back(row);
      return ChunkResult::consumed;
    }
    if (type == chunk::kImageData) {
      row.note = size >= 6 ? "vds image data: MCUs " + std::to_string(load_le32(payload)) + "+" +
                                 std::to_string(payload[4] | (payload[5] << 8))
                           : "vds image data (malformed)";
      c->rows.push_back(row);
      return ChunkResult::consumed;
    }
    if (type == chunk::kWalkParams) {
      WalkParams w;
      if (walk_params_from_bytes(payload, size, &w) == Status::ok) {
        row.note = "walkthrough: " + std::to_string(w.slots) + " triangle slots, " + std::to_string(w.views) + " views of " +
                   std::to_string(w.view_width) + "x" + std::to_string(w.view_height) + ", records of up to " +
                   std::to_string(w.frames_per_record) + " frames; ";
        row.note += w.rate_bytes == 0 ? std::string("untimed")
                                      : "shaped for " + std::to_string(w.rate_bytes) + " bytes/s into a " +
                                            std::to_string(w.buffer_bytes) + "-byte window, pre-roll " +
                                            std::to_string(w.preroll_ms) + " ms";
      } else {
        row.note = "walkthrough parameters (malformed)";
      }
      c->rows.push_back(row);
      return ChunkResult::consumed;
    }
    if (type == chunk::kTerrainParams) {
      terrain::Params t;
      if (terrain::params_from_bytes(payload, size, &t) == Status::ok) {
        row.note = "terrain: " + std::to_string(t.cells_x) + "x" + std::to_string(t.cells_y) + " cells, quantiser " +
                   std::to_string(t.quantiser) + ", a store of " + std::to_string(t.store_units * 2u) + " bytes, " +
                   std::to_string(1 << t.cache_log2) + "-cell block cache, pose every " + std::to_string(t.pose_period) +
                   " frames";
      } else {
        row.note = "terrain parameters (malformed)";
      }
      c->rows.push_back(row);
      return ChunkResult::consumed;
    }
    if (type == chunk::kTerrainFlight || type == chunk::kTerrainElevation || type == chunk::kTerrainTexture ||
        type == chunk::kTerrainFrame) {
      row.note = type == chunk::kTerrainFlight      ? "terrain: the flight's camera keys"
                 : type == chunk::kTerrainElevation ? (size > 0 && payload[0] == 0 ? "terrain: the coarse elevation"
                                                                                    : "terrain: rows of the fine elevation")
                 : type == chunk::kTerrainTexture   ? "terrain: a texture update"
                                                    : "terrain: draw a frame";
      c->rows.push_back(row);
      return ChunkResult::consumed;
    }
    if (type == chunk::kJpeg) {
      row.note = "baseline JPEG bytes";
      c->rows.push_back(row);
      return ChunkResult::consumed;
    }
    row.note = "not interpreted by this version (skipped)";
    c->rows.push_back(row);
    return ChunkResult::unknown;
  };
  Status s = parser.init(arena, o.chunk_buffer, sink);
  if (s != Status::ok) throw Failure(kExitUsage, std::string("cannot start parser: ") + status_name(s));
  s = parser.feed(bytes.data(), bytes.size());
  if (s == Status::more_input) s = parser.finish();

  if (parser.have_header()) {
    const StreamHeader& h = parser.header();
    std::printf("%s: vds stream, container %u.%u, %zu bytes\n", o.file.c_str(), h.version_major, h.version_minor,
                bytes.size());
    std::printf("  mode               %s%s\n", mode_name(h.mode),
                (h.flags & kHeaderFlagInteractive) ? " (interactive: needs the back-channel)" : "");
    std::printf("  frame size         %ux%u\n", h.width, h.height);
    if (h.frame_period_us)
      std::printf("  timing             %" PRIu32 " us per frame (%.3f frames/s)\n", h.frame_period_us,
                  1e6 / static_cast<double>(h.frame_period_us));
    else
      std::printf("  timing             none\n");
    std::printf("  frames             %" PRIu32 "%s\n", h.frame_count, h.frame_count ? "" : " (unknown or unbounded)");
    if (h.focal_x_q16 || h.focal_y_q16)
      std::printf("  camera             f=(%s, %s) px, centre=(%s, %s) px, near %s, far %s\n", q16(h.focal_x_q16).c_str(),
                  q16(h.focal_y_q16).c_str(), q16(h.center_x_q16).c_str(), q16(h.center_y_q16).c_str(),
                  q16(h.near_q16).c_str(), q16(h.far_q16).c_str());
    else
      std::printf("  camera             none\n");
    std::printf("  budgets            max chunk payload %" PRIu32 " B, decoder workspace %" PRIu32
                " B, vertices %" PRIu32 ", triangles %" PRIu32 "\n",
                h.max_chunk_payload, h.workspace_bytes, h.max_vertices, h.max_triangles);
    std::printf("  client needs       %" PRIu32 " B of workspace (chunk buffer + decoder)\n",
                h.max_chunk_payload + h.workspace_bytes);
  }
  if (!o.summary && !col.rows.empty()) {
    std::printf("  chunks:\n    %10s  %-6s %10s  %s\n", "offset", "type", "payload", "");
    for (const ChunkRow& r : col.rows)
      std::printf("    %10" PRIu64 "  %-6s %10" PRIu32 "  %s\n", r.offset, enc::fourcc_name(r.type).c_str(), r.size,
                  r.note.c_str());
  }
  if (!col.mesh.empty()) std::printf("%s", col.mesh.table().c_str());
  for (const std::string& m : col.meta) {
    size_t start = 0;
    while (start < m.size()) {
      size_t nl = m.find('\n', start);
      if (nl == std::string::npos) nl = m.size();
      std::printf("  meta               %s\n", m.substr(start, nl - start).c_str());
      start = nl + 1;
    }
  }
  if (s != Status::ok) {
    char where[64];
    std::snprintf(where, sizeof where, " at byte %" PRIu64, parser.error_offset());
    throw Failure(kExitBadInput, o.file + ": " + status_name(s) + where + ": " + parser.error_detail());
  }
  std::printf("  total              %" PRIu32 " chunks (HEAD and END included), %" PRIu32 " skipped as unknown\n",
              parser.chunks(), parser.chunks_skipped());
}

}  // namespace

void add_info(CLI::App& app) {
  auto opts = std::make_shared<InfoOptions>();
  CLI::App* sub = app.add_subcommand(
      "info", "Print a stream's header, budgets and chunks (checks every CRC), or a scene's faces, textures and spawn points");
  sub->add_option("FILE", opts->file, "vds stream, or a scene: a .bsp file or an OpenArena map name (oa_dm4)")->required();
  sub->add_option("--workspace", opts->workspace, "Workspace of the client to check against, bytes")
      ->capture_default_str()->check(CLI::PositiveNumber);
  sub->add_option("--chunk-buffer", opts->chunk_buffer, "Chunk buffer of the client to check against, bytes")
      ->capture_default_str()->check(CLI::PositiveNumber);
  sub->add_flag("--summary", opts->summary, "Header and totals only, no chunk list");
  sub->callback([opts] { run_info(*opts); });
}

}  // namespace vds::cli
