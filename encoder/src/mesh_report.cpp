// vds encoder, progressive mesh coding: the per-level table and the chunk
// summary of a mesh stream (`vds encode-mesh`, `vds info`).
#include "vds/enc/mesh_encoder.h"

#include <cstdio>
#include <string>
#include <vector>

namespace vds::enc {

std::string format_mesh_table(const std::vector<MeshLevelStats>& levels, size_t stream_bytes) {
  std::string s;
  char line[256];
  std::snprintf(line, sizeof line, "%5s %8s %8s %7s %7s %9s %9s %10s %9s\n", "level", "dV", "dT", "C/dT", "G/dT",
                "(C+G)/dT", "bytes", "cum.bytes", "vertices");
  s += line;
  uint64_t cum = 0, c_sum = 0, g_sum = 0, dt_sum = 0, dv_sum = 0;
  for (const MeshLevelStats& l : levels) {
    cum += l.chunk_bytes;
    if (l.level == 0) {
      std::snprintf(line, sizeof line, "%5s %8u %8u %7s %7s %9.2f %9llu %10llu %9u\n", "base", l.vertices_added,
                    l.triangles_added, "-", "-",
                    l.triangles_added ? 8.0 * double(l.connectivity_bytes + l.geometry_bytes) / l.triangles_added : 0.0,
                    static_cast<unsigned long long>(l.chunk_bytes), static_cast<unsigned long long>(cum), l.vertices);
    } else {
      const double dt = l.triangles_added ? double(l.triangles_added) : 1.0;
      char level[16];
      std::snprintf(level, sizeof level, l.tail ? "%uT" : "%u", l.level);
      std::snprintf(line, sizeof line, "%5s %8u %8u %7.2f %7.2f %9.2f %9llu %10llu %9u\n", level, l.vertices_added,
                    l.triangles_added, 8.0 * double(l.connectivity_bytes) / dt, 8.0 * double(l.geometry_bytes) / dt,
                    8.0 * double(l.connectivity_bytes + l.geometry_bytes) / dt,
                    static_cast<unsigned long long>(l.chunk_bytes), static_cast<unsigned long long>(cum), l.vertices);
      c_sum += l.connectivity_bytes;
      g_sum += l.geometry_bytes;
      dt_sum += l.triangles_added;
      dv_sum += l.vertices_added;
    }
    s += line;
  }
  if (dt_sum) {
    std::snprintf(line, sizeof line, "%5s %8llu %8llu %7.2f %7.2f %9.2f   (levels 1..%u)\n", "avg",
                  static_cast<unsigned long long>(dv_sum), static_cast<unsigned long long>(dt_sum),
                  8.0 * double(c_sum) / double(dt_sum), 8.0 * double(g_sum) / double(dt_sum),
                  8.0 * double(c_sum + g_sum) / double(dt_sum), levels.empty() ? 0u : levels.back().level);
    s += line;
  }
  if (!levels.empty() && levels.back().tail) {
    std::snprintf(line, sizeof line,
                  "(level %uT: the single-rate tail; it sends the whole mesh again, dV and dT are net)\n",
                  levels.back().level);
    s += line;
  }
  if (!levels.empty() && levels.back().triangles) {
    std::snprintf(line, sizeof line,
                  "total: %zu bytes = %.3f bits/triangle, %.3f bits/vertex (%u vertices, %u triangles, %zu levels)\n",
                  stream_bytes, 8.0 * double(stream_bytes) / levels.back().triangles,
                  8.0 * double(stream_bytes) / levels.back().vertices, levels.back().vertices,
                  levels.back().triangles, levels.size() - 1);
    s += line;
  }
  return s;
}

namespace {

// A level or tail chunk's two substreams, from its connectivity size on.
void count_substreams(MeshLevelStats& l, const uint8_t* p, const uint8_t* end, uint32_t size) {
  uint32_t conn = 0;
  if (read_varint(p, end, &conn) != Status::ok || conn > static_cast<uint32_t>(end - p)) return;
  l.connectivity_bytes += conn;
  l.geometry_bytes += static_cast<uint64_t>(end - p) - conn;
  l.chunk_bytes += size + kChunkHeadBytes + kChunkTailBytes;
  ++l.chunks;
}

}  // namespace

bool MeshChunkSummary::add(uint32_t type, const uint8_t* payload, uint32_t size) {
  const uint8_t* p = payload;
  const uint8_t* end = payload + size;
  if (type == chunk::kMeshHeader) {
    if (mesh_header_from_bytes(payload, size, &header_) != Status::ok) return true;
    have_header_ = true;
    levels_.assign(1, MeshLevelStats{});
    levels_[0].vertices_added = levels_[0].vertices = header_.base_vertices;
    levels_[0].triangles_added = levels_[0].triangles = header_.base_triangles;
    return true;
  }
  if (!have_header_) return type == chunk::kMeshBase || type == chunk::kMeshLevel || type == chunk::kMeshTail;
  if (type == chunk::kMeshTail) {
    uint32_t first = 0, count = 0;
    if (!header_.tail() || read_varint(p, end, &first) != Status::ok || read_varint(p, end, &count) != Status::ok)
      return true;
    const uint32_t level = header_.levels;
    if (levels_.size() <= level) levels_.resize(level + 1);
    MeshLevelStats& l = levels_[level];
    l.level = level;
    l.tail = true;
    count_substreams(l, p, end, size);
    return true;
  }
  if (type == chunk::kMeshBase) {
    uint32_t first = 0, count = 0;
    if (read_varint(p, end, &first) != Status::ok || read_varint(p, end, &count) != Status::ok) return true;
    levels_[0].connectivity_bytes += static_cast<uint64_t>(end - p);
    levels_[0].chunk_bytes += size + kChunkHeadBytes + kChunkTailBytes;
    ++levels_[0].chunks;
    return true;
  }
  if (type == chunk::kMeshLevel) {
    uint32_t level = 0, first = 0, count = 0, dv = 0, dt = 0;
    if (read_varint(p, end, &level) != Status::ok || read_varint(p, end, &first) != Status::ok ||
        read_varint(p, end, &count) != Status::ok || level == 0 || level > header_.levels)
      return true;
    if (levels_.size() <= level) levels_.resize(level + 1);
    MeshLevelStats& l = levels_[level];
    l.level = level;
    if (first == 0) {
      if (read_varint(p, end, &dv) != Status::ok || read_varint(p, end, &dt) != Status::ok || p >= end) return true;
      l.weight_q4 = *p++;
      l.vertices_added = dv;
      l.triangles_added = dt;
    }
    count_substreams(l, p, end, size);
    return true;
  }
  return false;
}

std::string MeshChunkSummary::table() const {
  if (!have_header_) return "";
  std::vector<MeshLevelStats> rows = levels_;
  uint32_t v = 0, t = 0;
  for (MeshLevelStats& r : rows) {
    if (r.tail) {  // net of the levels before it
      r.vertices_added = header_.vertices - v;
      r.triangles_added = header_.triangles - t;
    }
    v += r.vertices_added;
    t += r.triangles_added;
    r.vertices = v;
    r.triangles = t;
  }
  char line[200];
  std::snprintf(line, sizeof line,
                "progressive mesh: %u-bit grid, %s coder, %s predictor, %u levels, max degree %u, up %s\n",
                header_.bits, header_.coder == MeshCoder::arith ? "arithmetic" : "Huffman",
                mesh_predictor_name(header_.predictor), header_.levels, header_.max_degree,
                mesh_up_name(header_.up));
  uint64_t bytes = 0;
  for (const MeshLevelStats& r : rows) bytes += r.chunk_bytes;
  return std::string(line) + format_mesh_table(rows, bytes) +
         "(C, G: connectivity and geometry substream bits; bytes: the level's chunks with framing;\n"
         " the total above counts mesh chunks only, not HEAD/MSHH/END)\n";
}

}  // namespace vds::enc
