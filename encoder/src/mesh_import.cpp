// vds encoder: mesh file import (assimp for OBJ/PLY/glTF/3DS/..., libdraco
// for .drc), bounds, the Draco-compatible quantisation grid and PLY/OBJ export.
#include "vds/enc/mesh_import.h"

#include <algorithm>
#include <cstring>
#include <filesystem>
#include <cmath>
#include <cstdio>
#include <memory>
#include <set>
#include <stdexcept>

#include <assimp/Importer.hpp>
#include <assimp/postprocess.h>
#include <assimp/scene.h>
#include <draco/compression/decode.h>
#include <draco/compression/encode.h>
#include <draco/mesh/triangle_soup_mesh_builder.h>
#include <draco/core/decoder_buffer.h>

#include "assimp_read.h"
#include "text.h"
#include "vds/enc/stream_writer.h"

namespace vds::enc {
namespace {

// The importer set up for a mesh: positions and faces only (no normals, UVs
// or materials are needed, and the importer must not weld: we weld by our
// own rule).
void configure(Assimp::Importer& importer) {
  importer.SetPropertyInteger(AI_CONFIG_PP_RVC_FLAGS, aiComponent_NORMALS | aiComponent_TANGENTS_AND_BITANGENTS |
                                                          aiComponent_COLORS | aiComponent_TEXCOORDS |
                                                          aiComponent_BONEWEIGHTS | aiComponent_ANIMATIONS |
                                                          aiComponent_TEXTURES | aiComponent_LIGHTS |
                                                          aiComponent_CAMERAS | aiComponent_MATERIALS);
}

// Assimp validates what its loader built (face indices inside their mesh,
// counts matching arrays) before any other step runs on it; triangulation
// and the node transforms then work on a valid scene.
constexpr unsigned kImportSteps = aiProcess_ValidateDataStructure | aiProcess_Triangulate |
                                  aiProcess_PreTransformVertices | aiProcess_RemoveComponent;

Mesh from_scene(const aiScene* scene, MeshRepairReport* report) {
  Mesh m;
  size_t non_triangles = 0;
  for (unsigned mi = 0; mi < scene->mNumMeshes; ++mi) {
    const aiMesh* am = scene->mMeshes[mi];
    const uint32_t base = static_cast<uint32_t>(m.positions.size());
    for (unsigned i = 0; i < am->mNumVertices; ++i)
      m.positions.push_back({am->mVertices[i].x, am->mVertices[i].y, am->mVertices[i].z});
    for (unsigned f = 0; f < am->mNumFaces; ++f) {
      const aiFace& face = am->mFaces[f];
      if (face.mNumIndices != 3) {
        ++non_triangles;
        continue;
      }
      m.triangles.push_back({base + face.mIndices[0], base + face.mIndices[1], base + face.mIndices[2]});
    }
  }
  if (report) {
    report->input_vertices = m.positions.size();
    report->input_faces = m.triangles.size();
    report->non_triangle_primitives = non_triangles;
  }
  return m;
}

bool is_draco(const uint8_t* data, size_t size) { return size >= 5 && std::memcmp(data, "DRACO", 5) == 0; }

// A mesh file's bytes, checked and imported. `root` is the folder whose
// files the importer may open besides these bytes (empty: none).
Mesh load_bytes(const uint8_t* data, size_t size, const std::string& name, const std::string& hint,
                const std::filesystem::path& root, MeshRepairReport* report) {
  if (size == 0) throw std::runtime_error(name + ": the file is empty");
  if (hint == "drc" || is_draco(data, size)) {
    Mesh m = decode_draco(data, size, name);
    if (report) {
      report->input_vertices = m.positions.size();
      report->input_faces = m.triangles.size();
    }
    return m;
  }
  Assimp::Importer importer;
  configure(importer);
  const aiScene* scene = read_with_assimp(importer, data, size, name, hint, root, kImportSteps);
  return from_scene(scene, report);
}

}  // namespace

Mesh decode_draco(const uint8_t* data, size_t size, const std::string& what) {
  draco::DecoderBuffer buffer;
  buffer.Init(reinterpret_cast<const char*>(data), size);
  draco::Decoder decoder;
  auto result = decoder.DecodeMeshFromBuffer(&buffer);
  if (!result.ok()) throw std::runtime_error(what + ": not a Draco mesh: " + result.status().error_msg_string());
  std::unique_ptr<draco::Mesh> dm = std::move(result).value();
  const draco::PointAttribute* pos = dm->GetNamedAttribute(draco::GeometryAttribute::POSITION);
  if (pos == nullptr || pos->num_components() < 3)
    throw std::runtime_error(what + ": Draco mesh has no 3-component position attribute");
  // Numbers only: a boolean "position" is not one (and reading it as one is
  // undefined behaviour inside libdraco's conversion).
  if (pos->data_type() < draco::DT_INT8 || pos->data_type() > draco::DT_FLOAT64)
    throw std::runtime_error(what + ": Draco position attribute is not numeric (type " +
                             std::to_string(static_cast<int>(pos->data_type())) + ")");
  Mesh m;
  m.positions.resize(dm->num_points());
  for (uint32_t i = 0; i < dm->num_points(); ++i) {
    float v[3] = {0, 0, 0};
    const draco::AttributeValueIndex at = pos->mapped_index(draco::PointIndex(i));
    if (at.value() >= pos->size() || !pos->ConvertValue<float, 3>(at, v))
      throw std::runtime_error(what + ": Draco point " + std::to_string(i) + " has no readable position");
    m.positions[i] = {v[0], v[1], v[2]};
  }
  m.triangles.resize(dm->num_faces());
  for (uint32_t f = 0; f < dm->num_faces(); ++f) {
    const draco::Mesh::Face& face = dm->face(draco::FaceIndex(f));
    for (int k = 0; k < 3; ++k)
      if (face[k].value() >= dm->num_points())
        throw std::runtime_error(what + ": Draco face " + std::to_string(f) + " refers to point " +
                                 std::to_string(face[k].value()) + " of " + std::to_string(dm->num_points()));
    m.triangles[f] = {face[0].value(), face[1].value(), face[2].value()};
  }
  return m;
}

std::vector<uint8_t> encode_draco(const Mesh& m, int qp, int cl) {
  draco::TriangleSoupMeshBuilder builder;
  builder.Start(static_cast<int>(m.triangles.size()));
  const int att = builder.AddAttribute(draco::GeometryAttribute::POSITION, 3, draco::DT_FLOAT32);
  for (size_t f = 0; f < m.triangles.size(); ++f) {
    float v[3][3];
    for (int c = 0; c < 3; ++c)
      for (int k = 0; k < 3; ++k) v[c][k] = static_cast<float>(m.positions[m.triangles[f][c]][k]);
    builder.SetAttributeValuesForFace(att, draco::FaceIndex(static_cast<uint32_t>(f)), v[0], v[1], v[2]);
  }
  std::unique_ptr<draco::Mesh> dm = builder.Finalize();
  if (!dm) throw std::runtime_error("encode_draco: cannot build the mesh");
  draco::Encoder encoder;
  encoder.SetAttributeQuantization(draco::GeometryAttribute::POSITION, qp);
  encoder.SetSpeedOptions(10 - cl, 10 - cl);
  draco::EncoderBuffer buffer;
  const draco::Status st = encoder.EncodeMeshToBuffer(*dm, &buffer);
  if (!st.ok()) throw std::runtime_error("encode_draco: " + st.error_msg_string());
  return std::vector<uint8_t>(buffer.data(), buffer.data() + buffer.size());
}

Mesh load_mesh_file(const std::string& path, MeshRepairReport* report) {
  const std::vector<uint8_t> bytes = read_file(path);
  std::error_code ec;
  const std::filesystem::path root = std::filesystem::weakly_canonical(std::filesystem::absolute(path), ec).parent_path();
  Mesh m = load_bytes(bytes.data(), bytes.size(), path, extension_of(path), ec ? std::filesystem::path() : root, report);
  if (m.triangles.empty()) throw std::runtime_error(path + ": holds no triangles");
  return m;
}

Mesh load_mesh_bytes(const uint8_t* data, size_t size, const std::string& name, MeshRepairReport* report) {
  Mesh m = load_bytes(data, size, name, extension_of(name), std::filesystem::path(), report);
  if (m.triangles.empty()) throw std::runtime_error(name + ": holds no triangles");
  return m;
}

Mesh import_mesh(const std::string& path, MeshRepairReport* report) {
  MeshRepairReport local;
  MeshRepairReport* r = report ? report : &local;
  const Mesh raw = load_mesh_file(path, r);
  Mesh fixed = repair_mesh(raw, r);
  if (fixed.triangles.empty()) throw std::runtime_error(path + ": no valid triangle left after repair");
  return fixed;
}

double Bounds::diagonal() const {
  double s = 0;
  for (int k = 0; k < 3; ++k) s += (max[k] - min[k]) * (max[k] - min[k]);
  return std::sqrt(s);
}

double Bounds::max_extent() const {
  return std::max({max[0] - min[0], max[1] - min[1], max[2] - min[2]});
}

Bounds mesh_bounds(const Mesh& m) {
  Bounds b;
  if (m.positions.empty()) return b;
  b.min = b.max = m.positions[0];
  for (const auto& p : m.positions)
    for (int k = 0; k < 3; ++k) {
      b.min[k] = std::min(b.min[k], p[k]);
      b.max[k] = std::max(b.max[k], p[k]);
    }
  return b;
}

std::array<double, 3> Quantisation::to_model(const std::array<int32_t, 3>& q) const {
  return {origin[0] + q[0] * step, origin[1] + q[1] * step, origin[2] + q[2] * step};
}

Quantisation make_quantisation(const Bounds& b, int bits) {
  if (bits < 2 || bits > 16) throw std::invalid_argument("quantisation bits must be 2..16");
  Quantisation q;
  q.bits = bits;
  q.origin = b.min;
  const double extent = b.max_extent();
  q.step = extent > 0 ? extent / static_cast<double>((1u << bits) - 1) : 1.0;
  return q;
}

std::vector<std::array<int32_t, 3>> quantise(const Mesh& m, const Quantisation& q) {
  const int32_t top = static_cast<int32_t>((1u << q.bits) - 1);
  std::vector<std::array<int32_t, 3>> out(m.positions.size());
  for (size_t i = 0; i < m.positions.size(); ++i)
    for (int k = 0; k < 3; ++k) {
      const double v = std::floor((m.positions[i][k] - q.origin[k]) / q.step + 0.5);
      out[i][k] = static_cast<int32_t>(std::clamp(v, 0.0, static_cast<double>(top)));
    }
  return out;
}

void write_ply(const std::string& path, const Mesh& m) {
  std::string s;
  s += "ply\nformat ascii 1.0\nelement vertex " + std::to_string(m.positions.size()) +
       "\nproperty float x\nproperty float y\nproperty float z\nelement face " + std::to_string(m.triangles.size()) +
       "\nproperty list uchar int vertex_indices\nend_header\n";
  char line[128];
  for (const auto& p : m.positions) {
    std::snprintf(line, sizeof line, "%.9g %.9g %.9g\n", p[0], p[1], p[2]);
    s += line;
  }
  for (const auto& t : m.triangles) {
    std::snprintf(line, sizeof line, "3 %u %u %u\n", t[0], t[1], t[2]);
    s += line;
  }
  write_file(path, std::span<const uint8_t>(reinterpret_cast<const uint8_t*>(s.data()), s.size()));
}

void write_obj(const std::string& path, const Mesh& m) {
  std::string s;
  char line[128];
  for (const auto& p : m.positions) {
    std::snprintf(line, sizeof line, "v %.9g %.9g %.9g\n", p[0], p[1], p[2]);
    s += line;
  }
  for (const auto& t : m.triangles) {
    std::snprintf(line, sizeof line, "f %u %u %u\n", t[0] + 1, t[1] + 1, t[2] + 1);
    s += line;
  }
  write_file(path, std::span<const uint8_t>(reinterpret_cast<const uint8_t*>(s.data()), s.size()));
}

}  // namespace vds::enc
