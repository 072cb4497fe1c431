// A textured model as one model-mode stream (vds/enc/model_stream.h).
#include "vds/enc/model_stream.h"

#include "vds/enc/model_render.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <array>
#include <map>
#include <memory>
#include <stdexcept>

#include "host_player.h"
#include "stream_chunks.h"
#include "vds/bytes.h"
#include "vds/container.h"
#include "vds/enc/arith_encoder.h"
#include "vds/enc/stream_writer.h"
#include "vds/mesh_colors.h"
#include "vds/model_view.h"
#include "vds/player.h"
#include "vds/render_camera.h"

namespace vds::enc {
namespace {

// The mesh stream's chunks, HEAD and END left out.
std::vector<StreamChunk> body_chunks(std::span<const uint8_t> s) {
  std::vector<StreamChunk> out;
  for (const StreamChunk& c : stream_chunks(s))
    if (c.type != chunk::kHeader && c.type != chunk::kEnd) out.push_back(c);
  return out;
}

// The client's mesh after the whole geometry stream: its triangles (3 per
// face, the client's vertex numbers).
std::vector<uint32_t> client_triangles(std::span<const uint8_t> stream, uint32_t* vertices,
                                       std::vector<std::array<uint16_t, 3>>* grid) {
  HostPlayer host;
  const Status s = host.play(stream);
  const MeshState& m = host.player->mesh.mesh();
  if (s != Status::ok || !host.player->mesh.complete())
    throw std::logic_error(std::string("model stream: the client does not decode the geometry: ") + status_name(s));
  std::vector<uint32_t> tri(3 * size_t{m.triangle_count()});
  for (size_t c = 0; c < tri.size(); ++c) tri[c] = m.corner_vertex(static_cast<uint32_t>(c));
  *vertices = m.vertex_count();
  grid->resize(m.vertex_count());
  for (uint32_t v = 0; v < m.vertex_count(); ++v)
    for (int a = 0; a < 3; ++a) (*grid)[v][a] = m.positions()[3 * v + a];
  return tri;
}

// `model` renumbered as the client holds its mesh: the client's vertex d
// is the repaired mesh's vertex order[d], at a position of the model's;
// the client's face (a, b, c) is the model's face over those vertices,
// its corners' attributes turned to start at a.
TexturedModel in_client_order(const TexturedModel& model, const Mesh& repaired, const std::vector<uint32_t>& order,
                              const std::vector<uint32_t>& tri) {
  std::map<std::array<double, 3>, uint32_t> at;
  for (uint32_t v = 0; v < model.positions.size(); ++v) at.emplace(model.positions[v], v);
  std::vector<uint32_t> model_vertex(order.size());
  for (size_t d = 0; d < order.size(); ++d) {
    const auto it = at.find(repaired.positions.at(order[d]));
    if (it == at.end()) throw std::logic_error("model stream: a repaired vertex is not the model's");
    model_vertex[d] = it->second;
  }
  // Faces by their vertices, turned to start at the smallest.
  auto key = [](uint32_t a, uint32_t b, uint32_t c) {
    const uint32_t m = std::min({a, b, c});
    return m == a ? std::array<uint32_t, 3>{a, b, c} : (m == b ? std::array<uint32_t, 3>{b, c, a} : std::array<uint32_t, 3>{c, a, b});
  };
  std::map<std::array<uint32_t, 3>, std::vector<uint32_t>> faces;
  for (uint32_t f = 0; f < model.triangles.size(); ++f) {
    const auto& t = model.triangles[f];
    faces[key(t[0], t[1], t[2])].push_back(f);
  }
  TexturedModel out;
  out.name = model.name;
  out.materials = model.materials;
  out.textures = model.textures;
  out.texture_files = model.texture_files;
  for (uint32_t v : model_vertex) out.positions.push_back(model.positions[v]);
  for (size_t t = 0; 3 * t < tri.size(); ++t) {
    const uint32_t a = model_vertex.at(tri[3 * t]), b = model_vertex.at(tri[3 * t + 1]), c = model_vertex.at(tri[3 * t + 2]);
    auto it = faces.find(key(a, b, c));
    if (it == faces.end() || it->second.empty()) throw std::logic_error("model stream: a client face is not the model's");
    const uint32_t f = it->second.back();
    it->second.pop_back();
    const auto& mt = model.triangles[f];
    const int turn = mt[0] == a ? 0 : (mt[1] == a ? 1 : 2);
    out.triangles.push_back({tri[3 * t], tri[3 * t + 1], tri[3 * t + 2]});
    std::array<std::array<double, 2>, 3> uv{};
    std::array<std::array<double, 3>, 3> colour{};
    for (int k = 0; k < 3; ++k) {
      uv[k] = model.uv[f][(k + turn) % 3];
      colour[k] = model.colour[f][(k + turn) % 3];
    }
    out.uv.push_back(uv);
    out.colour.push_back(colour);
    out.material.push_back(model.material[f]);
  }
  return out;
}

// The MCVX payloads of the mesh stream: after chunk i (the key) that
// completes the base or a split level, the colours of the vertices it
// added — the final mesh's vertex samples of the vertices at their grid
// positions — coded as the client decodes them (mc::decode_vertex_colours).
std::map<size_t, std::vector<uint8_t>> vertex_colour_chunks(std::span<const uint8_t> stream,
                                                            const std::vector<std::array<uint16_t, 3>>& grid,
                                                            const std::vector<uint8_t>& final_ycc) {
  std::map<std::array<uint16_t, 3>, uint32_t> at;
  for (uint32_t v = 0; v < grid.size(); ++v) at.emplace(grid[v], v);
  HostPlayer host;
  Player& p = *host.player;
  const std::vector<StreamChunk> chunks = body_chunks(stream);
  std::map<size_t, std::vector<uint8_t>> out;
  std::array<std::vector<uint8_t>, 3> planes;
  for (auto& pl : planes) pl.assign(grid.size() + 1, 0);
  uint32_t coloured = 0, levels = 0;
  bool base = false;
  size_t fed = 0;
  for (size_t i = 0; i < chunks.size(); ++i) {
    const Status st = p.feed(stream.data() + fed, chunks[i].end - fed);
    fed = chunks[i].end;
    if (is_error(st)) throw std::logic_error("model stream: the client refused the geometry");
    const MeshState& m = p.mesh.mesh();
    const uint32_t nv = m.vertex_count();
    // The base, and each split level, once complete; the single-rate tail
    // numbers the vertices anew, so after it every vertex again.
    const bool done = (!base && p.mesh.drawable()) || (base && p.mesh.levels_done() != levels);
    base = p.mesh.drawable();
    levels = p.mesh.levels_done();
    if (!done) continue;
    if (p.mesh.header().tail() && p.mesh.levels_done() == p.mesh.header().levels) coloured = 0;
    if (nv == coloured) continue;
    if (nv > grid.size()) throw std::logic_error("model stream: a level has more vertices than the mesh");
    ArithEncoder enc;
    mc::VertexContexts vx;
    vx.reset();
    for (uint32_t v = coloured; v < nv; ++v) {
      const std::array<uint16_t, 3> g{m.positions()[3 * v], m.positions()[3 * v + 1], m.positions()[3 * v + 2]};
      const auto it = at.find(g);
      if (it == at.end()) throw std::logic_error("model stream: a level's vertex is not the mesh's");
      for (int c = 0; c < 3; ++c) {
        const int cls = c == 0 ? 0 : 1;
        const int32_t value = final_ycc[3 * size_t{it->second} + c];
        const int32_t r = value - mc::fan_prediction(m, planes[c].data(), v);
        enc.encode_signed(vx.zero[cls], vx.mag[cls], mc::VertexContexts::kMagCtx, r, mc::kDcCutoff, mc::kDcOrder);
        planes[c][v] = static_cast<uint8_t>(value);
      }
    }
    std::vector<uint8_t> payload(mc::kVertexChunkHeadBytes);
    for (int k = 0; k < 4; ++k) {
      payload[k] = static_cast<uint8_t>(coloured >> (8 * k));
      payload[4 + k] = static_cast<uint8_t>((nv - coloured) >> (8 * k));
    }
    const std::vector<uint8_t> body = enc.finish();
    payload.insert(payload.end(), body.begin(), body.end());
    out[i] = std::move(payload);
    coloured = nv;
  }
  return out;
}

size_t framed(size_t payload) { return kChunkHeadBytes + payload + kChunkTailBytes; }

// The stream: the mesh's chunks, each level's vertex colours after it,
// MCLH, then the levels r.sent says, coarsest first.
void assemble(ModelStreamResult& r, const std::map<size_t, std::vector<uint8_t>>& vertex_chunks, size_t max_chunk) {
  StreamWriter w(r.header);
  r.parts = ModelStreamParts{};
  const std::vector<StreamChunk> mesh_chunks = body_chunks(r.mesh.stream);
  for (size_t i = 0; i < mesh_chunks.size(); ++i) {
    w.add_chunk(mesh_chunks[i].type, mesh_chunks[i].payload);
    const auto vc = vertex_chunks.find(i);
    if (vc == vertex_chunks.end()) continue;
    if (vc->second.size() > max_chunk) throw std::invalid_argument("a level's vertex colours take more than a chunk");
    w.add_chunk(mc::kChunkVertices, vc->second);
    r.parts.vertex_colours += framed(vc->second.size());
    ++r.parts.vertex_chunks;
  }
  r.parts.geometry_end = w.size();
  w.add_chunk(mc::kChunkHeader, r.coded.header);
  r.parts.colors_header_end = w.size();
  r.parts.colors_header = framed(r.coded.header.size());
  r.parts.level_bytes.assign(r.coded.levels.size(), 0);
  r.parts.level_end.assign(r.coded.levels.size(), 0);
  for (size_t m = r.coded.levels.size(); m-- > 0;) {
    if (!r.sent[m]) continue;
    for (const auto& ch : r.coded.levels[m]) {
      w.add_chunk(mc::kChunkLevel, ch);
      r.parts.level_bytes[m] += framed(ch.size());
    }
    r.parts.level_end[m] = w.size();
  }
  // The orbit script: a turn in orbit_frames frames, from angle 0.
  for (uint32_t i = 0; i < r.orbit_frames; ++i) {
    const uint32_t angle = static_cast<uint32_t>((uint64_t{i} * 65536) / r.orbit_frames);
    const uint8_t a[2] = {static_cast<uint8_t>(angle & 0xFF), static_cast<uint8_t>(angle >> 8)};
    w.add_chunk(kModelOrbitChunk, a);
    r.parts.orbit += framed(sizeof a);
  }
  r.stream = w.finish();
  r.parts.geometry = r.stream.size() - r.parts.colors_header - r.parts.vertex_colours - r.parts.orbit;
  for (size_t b : r.parts.level_bytes) r.parts.geometry -= b;
}

struct Colours {
  double quality;
  MeshColorsModel mc;
  MccEncoded coded;
};

// The largest exponent each face of `dm` needs on a client (see
// ModelStreamOptions::samples_per_pixel): as the texture rule, R for
// R^2 / 2 samples over the face's area in pixels when nearest the
// client's camera, times the samples per pixel, to the next power of two.
std::vector<uint8_t> display_caps(const TexturedModel& dm, const Quantisation& q, const std::vector<std::array<uint16_t, 3>>& grid,
                                  const StreamHeader& h, double samples_per_pixel) {
  // World units (the model view's): 2^bits grid steps span 2 units, centred on the bounds.
  std::array<double, 3> lo{1e30, 1e30, 1e30}, hi{-1e30, -1e30, -1e30};
  for (const auto& g : grid)
    for (int a = 0; a < 3; ++a) {
      lo[a] = std::min<double>(lo[a], g[a]);
      hi[a] = std::max<double>(hi[a], g[a]);
    }
  const double unit = 2.0 / std::ldexp(1.0, q.bits);  // world units per grid step
  double radius = 0;
  for (const auto& g : grid) {
    double d2 = 0;
    for (int a = 0; a < 3; ++a) d2 += std::pow((g[a] - (lo[a] + hi[a]) / 2) * unit, 2);
    radius = std::max(radius, std::sqrt(d2));
  }
  const double nearest = std::max(0.25, kModelViewDistanceQ16 / 65536.0 - radius);
  const double px_per_unit = std::max<int32_t>(h.height, kCameraMinFocalPx) / nearest;
  std::vector<std::array<double, 3>> positions(grid.size());
  for (size_t i = 0; i < grid.size(); ++i)
    for (int a = 0; a < 3; ++a) positions[i][a] = grid[i][a] * unit;
  return display_face_caps(positions, dm.triangles, px_per_unit, samples_per_pixel);
}

Colours colours_at(const TexturedModel& dm, const ModelStreamOptions& o, double quality, size_t max_chunk,
                   const ModelViews& views, const std::vector<ModelFrame>& reference) {
  MeshColorsOptions co = o.colors;
  if (!o.fixed_density) co.density = density_for_quality(quality);
  MccOptions mo = o.codec;
  mo.max_chunk = max_chunk;
  mo.vertex_colours_outside = o.vertex_colours;  // every vertex's colour came with it (MCVX)
  if (o.measure_colours && !mo.paper) {
    ColourChoice choice = choose_colours(dm, co, quality, mo, views, reference);
    return Colours{quality, std::move(choice.mc), std::move(choice.coded)};
  }
  Colours c{quality, o.coarser_faces && !mo.paper ? to_mesh_colors_rd(dm, co, quality, mo) : to_mesh_colors(dm, co), {}};
  c.coded = encode_mesh_colors(c.mc, quality, mo);
  return c;
}


size_t stream_bytes(const MeshEncodeResult& mesh, const MccEncoded& coded) {
  size_t n = mesh.stream.size() + framed(coded.header.size());
  for (const auto& level : coded.levels)
    for (const auto& c : level) n += framed(c.size());
  return n;
}

}  // namespace

ModelStreamResult encode_model_stream(const TexturedModel& model, const ModelStreamOptions& o) {
  ModelStreamResult r;
  Mesh mesh;
  mesh.positions = model.positions;
  mesh.triangles = model.triangles;
  const Mesh repaired = repair_mesh(mesh, &r.repair);
  r.mesh = encode_mesh(repaired, o.mesh);
  uint32_t vertices = 0;
  std::vector<std::array<uint16_t, 3>> grid;
  const std::vector<uint32_t> tri = client_triangles(r.mesh.stream, &vertices, &grid);
  if (vertices != r.mesh.vertex_order.size()) throw std::logic_error("model stream: the client's vertex count differs");
  r.decoded = in_client_order(model, repaired, r.mesh.vertex_order, tri);
  if (o.orbit_frames > kModelOrbitMaxFrames) throw std::invalid_argument("an orbit of more than 4096 frames");
  r.orbit_frames = o.orbit_frames;
  ModelStreamOptions oc = o;
  if (o.samples_per_pixel > 0)
    oc.colors.face_max_res = display_caps(r.decoded, r.mesh.quantisation, grid, r.mesh.stream_header, o.samples_per_pixel);

  const size_t max_chunk = r.mesh.stream_header.max_chunk_payload;
  std::map<size_t, std::vector<uint8_t>> vertex_chunks;
  // The views the encoder's colour choices are measured from: 4 round the
  // model at the client's frame size.
  ModelViews choice_views;
  std::vector<ModelFrame> choice_reference;
  if (o.measure_colours && !o.codec.paper) {
    choice_views = orbit_views(r.decoded.positions, 4, r.mesh.stream_header.width, r.mesh.stream_header.height, 2,
                               r.mesh.mesh_header.up == MeshUp::z_plus ? 2 : 1);
    choice_reference = render_references(r.decoded, choice_views);
  }
  // The colours at quality q, coded (without the schedule: the bytes of every level).
  auto colour = [&](double q) {
    Colours c = colours_at(r.decoded, oc, q, max_chunk, choice_views, choice_reference);
    vertex_chunks.clear();
    if (o.vertex_colours) vertex_chunks = vertex_colour_chunks(r.mesh.stream, grid, c.mc.vertex_ycc);
    if (c.coded.header.size() > max_chunk)
      throw std::invalid_argument("the mesh colors header takes " + std::to_string(c.coded.header.size()) +
                                  " bytes, more than a chunk (" + std::to_string(max_chunk) + "): raise the chunk size");
    r.quality = c.quality;
    r.colors = std::move(c.mc);
    r.coded = std::move(c.coded);
    size_t n = stream_bytes(r.mesh, r.coded);
    for (const auto& [at, payload] : vertex_chunks) n += framed(payload.size());
    return n;
  };
  // The stream of the colours last coded, the rate schedule applied; the
  // PSNR of its finest picture as the schedule measured it (0 without).
  auto finish = [&]() {
    StreamHeader h = r.mesh.stream_header;
    const uint32_t faces = static_cast<uint32_t>(r.colors.face_res.size());
    const size_t extra = Player::model_colors_workspace_bytes(faces, vertices, r.colors.samples(0));
    if (h.workspace_bytes + extra > 0xFFFFFFFFu) throw std::invalid_argument("model too large for a client workspace");
    h.workspace_bytes = static_cast<uint32_t>(h.workspace_bytes + extra);
    r.header = h;
    r.sent.assign(r.coded.levels.size(), true);
    r.level_psnr.clear();
    assemble(r, vertex_chunks, max_chunk);
    if (o.schedule_views <= 0 || r.coded.levels.empty()) return 0.0;
    // The rate schedule: each level as the client shows it, measured; a
    // level no better than the best coarser one by 0.05 dB is not sent.
    TimelineOptions t;
    t.views = o.schedule_views;
    t.supersample = 2;
    t.colours_only = true;
    std::vector<double> psnr(r.coded.levels.size() + 1, -1);
    for (const TimelinePoint& p : model_timeline(model, r, t))
      if (p.colour_level >= 0 && p.colour_level <= r.colors.max_res) psnr[static_cast<size_t>(p.colour_level)] = p.psnr;
    double best = psnr.back();  // the vertex samples alone (MCLH)
    for (size_t m = r.coded.levels.size(); m-- > 0;) {
      r.sent[m] = psnr[m] > best + 0.05;
      if (r.sent[m]) best = psnr[m];
    }
    r.level_psnr = psnr;
    assemble(r, vertex_chunks, max_chunk);
    return best;
  };
  // The quality ladder of --bytes and --psnr: 1/8 to 64 in steps of sqrt(2).
  std::vector<double> ladder;
  for (int i = 0; i <= 18; ++i) ladder.push_back(0.125 * std::pow(2.0, i / 2.0));
  if (o.max_bytes > 0) {
    bool found = false;
    size_t bytes = 0;
    for (size_t i = 0; i < ladder.size() && !found; ++i) found = (bytes = colour(ladder[i])) <= o.max_bytes;
    if (!found)
      throw std::invalid_argument("no quality fits " + std::to_string(o.max_bytes) + " bytes (at quality 64: " +
                                  std::to_string(bytes) + ")");
    finish();
  } else if (o.min_psnr > 0) {
    if (o.schedule_views <= 0) throw std::invalid_argument("a PSNR target needs the rate schedule's measure");
    // The coarsest quality whose finest picture reaches the target: the
    // ladder bisected (finer qualities never measured worse on the test models).
    // lo: the coarsest known to reach it; hi: the finest known not to (or the end).
    size_t lo = 0, hi = ladder.size(), last = 0;
    colour(ladder[0]);
    const double finest = finish();
    if (finest < o.min_psnr) {
      char msg[160];
      std::snprintf(msg, sizeof msg, "no quality reaches %.2f dB (at quality 1/8: %.2f dB)", o.min_psnr, finest);
      throw std::invalid_argument(msg);
    }
    while (hi - lo > 1) {
      const size_t mid = (lo + hi) / 2;
      colour(ladder[mid]);
      last = mid;
      if (finish() >= o.min_psnr)
        lo = mid;
      else
        hi = mid;
    }
    if (last != lo) {  // the stream in hand is another quality's
      colour(ladder[lo]);
      finish();
    }
  } else {
    colour(o.quality);
    finish();
  }
  return r;
}

}  // namespace vds::enc
