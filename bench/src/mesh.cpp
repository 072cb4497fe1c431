// Benchmark of the progressive mesh codec against Draco on glmark2-data's
// bunny, horse and cat: stream sizes (vds default, the paper's coding, the
// real draco_encoder -qp Q -cl 10 on the same welded positions-only PLY),
// the per-level tables, rate-distortion after every level with Draco's
// point, host decode time against libdraco's decoder and the client
// workspace, all in one run. bench/run_mesh.sh runs it (and callgrind, and
// the plots) and keeps the output in bench/results/mesh.md.
//
//   bench_mesh [--models a,b,c] [--bits 10,12] [--out DIR] [--tmp DIR]
//              [--samples N] [--reps N] [--draco-encoder PATH]
//   bench_mesh --decode-once FILE.vds     (one decode, for callgrind)
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdarg>
#include <cstdlib>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

#include <draco/compression/decode.h>

#include "vds/container.h"
#include "vds/enc/mesh_encoder.h"
#include "vds/enc/mesh_import.h"
#include "vds/enc/mesh_metrics.h"
#include "vds/enc/stream_writer.h"
#include "vds/mesh.h"
#include "vds/player.h"

namespace {

using namespace vds;
using namespace vds::enc;
using Clock = std::chrono::steady_clock;

std::vector<std::string> split(const std::string& s, char sep) {
  std::vector<std::string> out;
  std::stringstream ss(s);
  std::string item;
  while (std::getline(ss, item, sep))
    if (!item.empty()) out.push_back(item);
  return out;
}

std::string base_name(const std::string& path) {
  std::string b = path.substr(path.find_last_of('/') + 1);
  return b.substr(0, b.find('.'));
}

std::string fmt(const char* f, ...) __attribute__((format(printf, 1, 2)));
std::string fmt(const char* f, ...) {
  char buf[1024];
  va_list ap;
  va_start(ap, f);
  std::vsnprintf(buf, sizeof buf, f, ap);
  va_end(ap);
  return buf;
}

// A client playing a whole stream through vds::Player, as the firmware
// does (the model drawn after the base and every level); keeps the mesh
// and the stream offset after the base and each level, and the time the
// player spent parsing and decoding (its frame records, with a nanosecond
// clock; the drawing not included).
struct Client {
  std::vector<uint8_t> ws;
  Player player;
  std::vector<std::pair<uint64_t, enc::Mesh>> levels;  // (bytes so far, mesh)
  const Quantisation* q = nullptr;
  bool keep = false;
  uint64_t decode_ns = 0;

  Status run(const std::vector<uint8_t>& s, const Quantisation* quant, bool keep_levels) {
    keep = keep_levels;
    q = quant;
    levels.clear();
    decode_ns = 0;
    const uint32_t ws_size = 64u << 20;
    if (ws.size() != ws_size) ws.assign(ws_size, 0);
    Arena arena(ws.data(), ws.size());
    PlayerConfig config = kClientPlayerConfig;
    config.max_chunk_bytes = 1u << 16;
    PlayerCallbacks cb;
    cb.ctx = this;
    cb.clock = [](void*) {
      return static_cast<uint64_t>(
          std::chrono::duration_cast<std::chrono::nanoseconds>(Clock::now().time_since_epoch()).count());
    };
    cb.frame_shown = [](void* ctx, const PlayedFrame& f) { static_cast<Client*>(ctx)->decode_ns += f.parse + f.decode; };
    cb.level = [](void* ctx, const PlayedLevel&) {
      auto* c = static_cast<Client*>(ctx);
      if (!c->keep) return;
      const MeshState& m = c->player.mesh.mesh();
      enc::Mesh out;
      out.positions.resize(m.vertex_count());
      for (uint32_t v = 0; v < m.vertex_count(); ++v) {
        int32_t qp[3];
        m.position(v, qp);
        out.positions[v] = c->q->to_model({qp[0], qp[1], qp[2]});
      }
      out.triangles.resize(m.triangle_count());
      for (uint32_t t = 0; t < m.triangle_count(); ++t)
        out.triangles[t] = {m.corner_vertex(3 * t), m.corner_vertex(3 * t + 1), m.corner_vertex(3 * t + 2)};
      // The chunk that completed the level is read to its end.
      c->levels.emplace_back(c->player.bytes_consumed(), std::move(out));
    };
    Status st = player.init(arena, config, cb);
    if (st != Status::ok) return st;
    st = player.feed(s.data(), s.size());
    if (st == Status::more_input) st = player.finish();
    if (st != Status::ok) return st;
    return player.mesh.complete() ? Status::ok : Status::truncated;
  }
};

// The fastest of several runs: the least disturbed by other work on the machine.
double fastest(const std::vector<double>& v) { return v.empty() ? 0 : *std::min_element(v.begin(), v.end()); }

struct Row {
  std::string model;
  int bits = 0;
  size_t vertices = 0, triangles = 0;
  size_t draco = 0, vds = 0, paper = 0, splits = 0;  // vds: with the single-rate tail; splits: without
  size_t levels = 0, base = 0;
  double vds_decode_ms = 0, draco_decode_ms = 0;
  double workspace_per_vertex = 0;
  uint32_t workspace = 0, chunk = 0;
  SurfaceDistance draco_dist, vds_full_dist;
  size_t bytes_first_second = 0, vertices_first_second = 0;
  double diag = 1;
  MeshBitBreakdown bits_vds, bits_paper, bits_splits;
};

int decode_once(const std::string& path) {
  const std::vector<uint8_t> s = read_file(path);
  Client c;
  const Status st = c.run(s, nullptr, false);
  const MeshDecoder& d = c.player.mesh;
  std::printf("%s: %s, %u vertices, %u base, %u splits\n", path.c_str(), status_name(st), d.mesh().vertex_count(),
              d.header().base_vertices, d.mesh().vertex_count() - d.header().base_vertices);
  return st == Status::ok ? 0 : 1;
}

}  // namespace

int main(int argc, char** argv) {
  std::string models = "/usr/share/glmark2/models/bunny.obj,/usr/share/glmark2/models/horse.3ds,"
                       "/usr/share/glmark2/models/cat.3ds";
  std::string bits_list = "10,12";
  std::string out_dir = "bench/results";
  std::string tmp = "/tmp/vds-bench-mesh";
  std::string draco_encoder = "draco_encoder";
  size_t samples = 60000;
  int reps = 15;
  for (int i = 1; i < argc; ++i) {
    const std::string a = argv[i];
    auto next = [&]() -> std::string {
      if (i + 1 >= argc) {
        std::fprintf(stderr, "%s needs a value\n", a.c_str());
        std::exit(2);
      }
      return argv[++i];
    };
    if (a == "--decode-once") return decode_once(next());
    if (a == "--models") models = next();
    else if (a == "--bits") bits_list = next();
    else if (a == "--out") out_dir = next();
    else if (a == "--tmp") tmp = next();
    else if (a == "--samples") samples = std::stoul(next());
    else if (a == "--reps") reps = std::stoi(next());
    else if (a == "--draco-encoder") draco_encoder = next();
    else {
      std::fprintf(stderr, "unknown option %s\n", a.c_str());
      return 2;
    }
  }
  if (std::system(("mkdir -p '" + tmp + "' '" + out_dir + "'").c_str()) != 0) return 1;

  std::string md_levels, md_rd, md_import;
  std::string csv = "model,bits,codec,level,vertices,triangles,bytes,hausdorff,rms,mean\n";
  std::vector<Row> rows;
  for (const std::string& path : split(models, ',')) {
    if (!std::ifstream(path).good()) {
      std::fprintf(stderr, "skipping %s: not installed\n", path.c_str());
      continue;
    }
    const std::string name = base_name(path);
    MeshRepairReport rep;
    const enc::Mesh mesh = import_mesh(path, &rep);
    md_import += "### " + name + " (`" + path + "`)\n\n```\n" + rep.summary() + "```\n\n";
    const double diag = mesh_bounds(mesh).diagonal();
    const std::string ply = tmp + "/" + name + ".ply";
    write_ply(ply, mesh);
    for (const std::string& bs : split(bits_list, ',')) {
      const int bits = std::stoi(bs);
      std::fprintf(stderr, "%s, %d bits\n", name.c_str(), bits);
      Row row;
      row.model = name;
      row.bits = bits;
      row.vertices = mesh.positions.size();
      row.triangles = mesh.triangles.size();
      row.diag = diag;
      // One line of mesh_rd.csv: a decoded mesh, its bytes and its distances.
      auto csv_row = [&](const char* codec, long level, const enc::Mesh& m, uint64_t bytes, const SurfaceDistance& d) {
        csv += fmt("%s,%d,%s,%ld,%zu,%zu,%llu,%.9g,%.9g,%.9g\n", name.c_str(), bits, codec, level, m.positions.size(),
                   m.triangles.size(), static_cast<unsigned long long>(bytes), d.hausdorff / diag, d.rms / diag,
                   d.mean / diag);
      };
      // Draco, the real command line tool, on the same welded mesh.
      const std::string drc = tmp + "/" + name + "_" + bs + ".drc";
      const std::string cmd = draco_encoder + " -i '" + ply + "' -o '" + drc + "' -qp " + bs + " -cl 10 > /dev/null";
      if (std::system(cmd.c_str()) != 0) {
        std::fprintf(stderr, "draco_encoder failed: %s\n", cmd.c_str());
        return 1;
      }
      const std::vector<uint8_t> drc_bytes = read_file(drc);
      row.draco = drc_bytes.size();
      const enc::Mesh draco_mesh = decode_draco(drc_bytes.data(), drc_bytes.size(), drc);
      row.draco_dist = surface_distance(mesh, draco_mesh, samples);
      {
        std::vector<double> t;
        for (int r = 0; r < reps; ++r) {
          draco::DecoderBuffer buf;
          buf.Init(reinterpret_cast<const char*>(drc_bytes.data()), drc_bytes.size());
          draco::Decoder d;
          const auto t0 = Clock::now();
          auto res = d.DecodeMeshFromBuffer(&buf);
          const auto t1 = Clock::now();
          if (!res.ok()) return 1;
          t.push_back(std::chrono::duration<double, std::milli>(t1 - t0).count());
        }
        row.draco_decode_ms = fastest(t);
      }
      csv_row("draco", -1, draco_mesh, row.draco, row.draco_dist);

      // vds as `vds encode-mesh` writes it (split levels, then the
      // single-rate tail), vds splits only, and the paper's coding.
      MeshEncodeOptions o;
      o.bits = bits;
      o.tail_fraction = kMeshDefaultTail;
      const MeshEncodeResult r = encode_mesh(mesh, o);
      MeshEncodeOptions so;
      so.bits = bits;
      const MeshEncodeResult sr = encode_mesh(mesh, so);
      MeshEncodeOptions po = paper_mesh_options();
      po.bits = bits;
      const MeshEncodeResult pr = encode_mesh(mesh, po);
      write_file(tmp + "/" + name + "_" + bs + ".vds", r.stream);
      write_file(tmp + "/" + name + "_" + bs + "_splits.vds", sr.stream);
      write_file(tmp + "/" + name + "_" + bs + "_paper.vds", pr.stream);
      row.vds = r.stream.size();
      row.splits = sr.stream.size();
      row.bits_splits = sr.bits;
      row.paper = pr.stream.size();
      row.levels = r.levels.size() - 1;
      row.base = r.mesh_header.base_vertices;
      row.bits_vds = r.bits;
      row.bits_paper = pr.bits;
      row.workspace = r.stream_header.workspace_bytes;
      row.chunk = r.stream_header.max_chunk_payload;
      row.workspace_per_vertex = double(row.workspace + row.chunk) / double(row.vertices);
      md_levels += fmt("### %s, %d bits — vds (arithmetic coder, area predictor, single-rate tail)\n\n```\n",
                       name.c_str(), bits) +
                   format_mesh_table(r.levels, r.stream.size()) + "```\n\n";
      md_levels += fmt("### %s, %d bits — vds splits only (`--tail 0`)\n\n```\n", name.c_str(), bits) +
                   format_mesh_table(sr.levels, sr.stream.size()) + "```\n\n";
      md_levels += fmt("### %s, %d bits — the paper's coding (Huffman, Laplacian predictor, eq. 1 priority)\n\n```\n",
                       name.c_str(), bits) +
                   format_mesh_table(pr.levels, pr.stream.size()) + "```\n\n";
      // Decode: every level kept for the distances; then timing runs.
      Client c;
      if (c.run(r.stream, &r.quantisation, true) != Status::ok) {
        std::fprintf(stderr, "decode failed\n");
        return 1;
      }
      {
        Client cs;
        if (cs.run(sr.stream, &sr.quantisation, true) != Status::ok) {
          std::fprintf(stderr, "decode failed\n");
          return 1;
        }
        for (size_t l = 0; l < cs.levels.size(); ++l) {
          const auto& [bytes, m] = cs.levels[l];
          const SurfaceDistance d = surface_distance(mesh, m, samples);
          csv_row("vds-splits", static_cast<long>(l), m, bytes, d);
        }
      }
      md_rd += fmt("### %s, %d bits\n\n| level | vertices | bytes | seconds at 2 KB/s | Hausdorff (%% diag) | RMS (%% diag) |\n"
                   "|---:|---:|---:|---:|---:|---:|\n",
                   name.c_str(), bits);
      for (size_t l = 0; l < c.levels.size(); ++l) {
        const auto& [bytes, m] = c.levels[l];
        const SurfaceDistance d = surface_distance(mesh, m, samples);
        if (l + 1 == c.levels.size()) row.vds_full_dist = d;
        if (bytes <= 2048) {
          row.bytes_first_second = bytes;
          row.vertices_first_second = m.positions.size();
        }
        md_rd += fmt("| %zu | %zu | %llu | %.2f | %.4f | %.4f |\n", l, m.positions.size(),
                     static_cast<unsigned long long>(bytes), bytes / 2048.0, 100 * d.hausdorff / diag,
                     100 * d.rms / diag);
        csv_row("vds", static_cast<long>(l), m, bytes, d);
      }
      md_rd += fmt("| Draco | %zu | %zu | %.2f | %.4f | %.4f |\n\n", draco_mesh.positions.size(), row.draco,
                   row.draco / 2048.0, 100 * row.draco_dist.hausdorff / diag, 100 * row.draco_dist.rms / diag);
      {
        std::vector<double> t;
        Client tc;
        for (int k = 0; k < reps; ++k) {
          const Status st = tc.run(r.stream, nullptr, false);
          if (st != Status::ok) return 1;
          t.push_back(static_cast<double>(tc.decode_ns) / 1e6);
        }
        row.vds_decode_ms = fastest(t);
      }
      rows.push_back(row);
    }
  }

  // The report.
  std::string md;
  md += "## Sizes against Draco (same welded, positions-only mesh; `draco_encoder -qp Q -cl 10`)\n\n";
  md += "| model | bits | V | T | Draco bytes | Draco b/T | vds bytes | vds b/T | vds / Draco | paper coding bytes | "
        "paper b/T | levels | base V (%) | vds splits only bytes | splits only b/T | splits only / Draco |\n"
        "|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|\n";
  for (const Row& r : rows)
    md += fmt("| %s | %d | %zu | %zu | %zu | %.2f | %zu | %.2f | **%.3f** | %zu | %.2f | %zu | %zu (%.2f %%) | %zu | "
              "%.2f | %.2f |\n",
              r.model.c_str(), r.bits, r.vertices, r.triangles, r.draco, 8.0 * r.draco / r.triangles, r.vds,
              8.0 * r.vds / r.triangles, double(r.vds) / r.draco, r.paper, 8.0 * r.paper / r.triangles, r.levels,
              r.base, 100.0 * r.base / r.vertices, r.splits, 8.0 * r.splits / r.triangles,
              double(r.splits) / r.draco);
  md += "\nGoal: vds / Draco <= 1.25, >= 12 levels, base <= 2 % of the vertices. vds: `vds encode-mesh`'s "
        "default, split levels up to 4 % of the vertices then the single-rate tail (levels counts it); vds "
        "splits only: vertex splits all the way (`--tail 0`).\n\n";
  md += "## Where the bits go (bits per vertex of the full mesh)\n\n";
  md += "| model | bits | coder | split flags | arc length | rotation | connectivity | positions | of which normal axis "
        "| base |\n|---|---:|---|---:|---:|---:|---:|---:|---:|---:|\n";
  for (const Row& r : rows)
    for (int p = 0; p < 2; ++p) {
      const MeshBitBreakdown& b = p ? r.bits_paper : r.bits_splits;
      const double n = double(r.vertices);
      md += fmt("| %s | %d | %s | %.2f | %.2f | %.2f | %.2f | %.2f | %s | %.2f |\n", r.model.c_str(), r.bits,
                p ? "paper (Huffman)" : "vds splits only", b.split_flags / n, b.split_shape / n,
                b.split_rotation / n, b.connectivity() / n, b.geometry / n,
                p ? "-" : fmt("%.2f", b.geometry_normal / n).c_str(), b.base / n);
    }
  md += "\nDraco's own split for comparison: connectivity about 1.3 bits/vertex, positions the rest.\n\n";
  md += "With the single-rate tail (bits per vertex of the full mesh):\n\n| model | bits | split levels "
        "(connectivity + positions + base) | tail connectivity | tail positions |\n|---|---:|---:|---:|---:|\n";
  for (const Row& r : rows) {
    const MeshBitBreakdown& b = r.bits_vds;
    const double n = double(r.vertices);
    md += fmt("| %s | %d | %.2f | %.2f | %.2f |\n", r.model.c_str(), r.bits,
              (b.connectivity() + b.geometry + b.base) / n, b.tail_connectivity / n, b.tail_geometry / n);
  }
  md += "\n";
  md += "## Client cost on the host\n\n| model | bits | vds decode (ms) | libdraco decode (ms) | workspace + chunk "
        "buffer (bytes) | bytes per vertex | first 2 KB (one second at 2 KB/s): bytes, vertices |\n"
        "|---|---:|---:|---:|---:|---:|---:|\n";
  for (const Row& r : rows)
    md += fmt("| %s | %d | %.2f | %.2f | %u + %u | %.1f | %zu B, %zu vertices |\n", r.model.c_str(), r.bits,
              r.vds_decode_ms, r.draco_decode_ms, r.workspace, r.chunk, r.workspace_per_vertex, r.bytes_first_second,
              r.vertices_first_second);
  md += fmt("\nFastest of %d runs each, in this one process (vds: `vds::Player`'s parse and decode records with a nanosecond clock, the drawing of each level excluded: container parser + "
            "mesh decoder from a buffer, the whole stream; Draco: `draco::Decoder::DecodeMeshFromBuffer`). The machine "
            "is shared: the fastest run is the least disturbed one.\n\n",
            reps);
  md += "## Full-resolution distortion (fraction of the bounding-box diagonal, %)\n\n| model | bits | vds Hausdorff | "
        "vds RMS | Draco Hausdorff | Draco RMS |\n|---|---:|---:|---:|---:|---:|\n";
  for (const Row& r : rows)
    md += fmt("| %s | %d | %.4f | %.4f | %.4f | %.4f |\n", r.model.c_str(), r.bits, 100 * r.vds_full_dist.hausdorff / r.diag,
              100 * r.vds_full_dist.rms / r.diag, 100 * r.draco_dist.hausdorff / r.diag, 100 * r.draco_dist.rms / r.diag);
  md += "\nBoth decode to the same quantisation grid (vds uses Draco's: the largest extent over 2^bits - 1 steps).\n\n";
  std::ofstream(out_dir + "/mesh_rd.csv") << csv;
  std::ofstream(out_dir + "/mesh_body.md") << md << "## Rate-distortion after each level\n\n" << md_rd
                                           << "## Per-level tables (the paper's form)\n\n" << md_levels
                                           << "## Import and repair\n\n" << md_import;
  std::fprintf(stderr, "wrote %s/mesh_body.md and %s/mesh_rd.csv\n", out_dir.c_str(), out_dir.c_str());
  return 0;
}
