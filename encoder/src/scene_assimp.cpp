// vds encoder: textured glTF 2.0 and OBJ scenes through assimp
// (vds/enc/scene.h, load_model_scene; the rule is stated there).
#include <algorithm>
#include <cmath>
#include <filesystem>
#include <stdexcept>

#include <assimp/material.h>
#include <assimp/postprocess.h>

#include "assimp_read.h"
#include "text.h"
#include "vds/enc/scene.h"
#include "vds/enc/stream_writer.h"

namespace vds::enc {

namespace {

uint8_t unit_to_byte(float v) { return static_cast<uint8_t>(std::lround(std::clamp(v, 0.0f, 1.0f) * 255)); }

Scene read_scene(const uint8_t* data, size_t size, const std::string& path, const std::filesystem::path& root) {
  std::error_code ec;
  const std::string ext = extension_of(path);
  Assimp::Importer importer;
  importer.SetPropertyInteger(AI_CONFIG_PP_RVC_FLAGS, aiComponent_TANGENTS_AND_BITANGENTS | aiComponent_BONEWEIGHTS |
                                                          aiComponent_ANIMATIONS | aiComponent_LIGHTS | aiComponent_CAMERAS);
  const unsigned steps = aiProcess_ValidateDataStructure | aiProcess_Triangulate | aiProcess_PreTransformVertices |
                         aiProcess_FlipUVs | aiProcess_RemoveComponent;
  const aiScene* as = read_with_assimp(importer, data, size, path, ext, root, steps);
  Scene s;
  s.name = path;
  s.kind = ext == "obj" ? "OBJ scene" : "glTF scene";
  s.metres_per_unit = 1;
  s.overbright = false;
  // A texture per material (the material's colour kept for its vertices).
  std::vector<std::array<uint8_t, 4>> colour(as->mNumMaterials, std::array<uint8_t, 4>{255, 255, 255, 255});
  std::vector<int> texture_of(as->mNumMaterials, -1);
  for (unsigned m = 0; m < as->mNumMaterials; ++m) {
    const aiMaterial* mat = as->mMaterials[m];
    aiColor4D c;
    if (mat->Get(AI_MATKEY_BASE_COLOR, c) == aiReturn_SUCCESS || mat->Get(AI_MATKEY_COLOR_DIFFUSE, c) == aiReturn_SUCCESS)
      colour[m] = {unit_to_byte(c.r), unit_to_byte(c.g), unit_to_byte(c.b), 255};
    aiString file;
    if (mat->GetTexture(aiTextureType_BASE_COLOR, 0, &file) != aiReturn_SUCCESS &&
        mat->GetTexture(aiTextureType_DIFFUSE, 0, &file) != aiReturn_SUCCESS)
      continue;
    SceneTexture t;
    t.name = file.C_Str();
    t.vertex_colour = true;
    if (const aiTexture* emb = as->GetEmbeddedTexture(file.C_Str())) {
      if (emb->mHeight != 0)
        throw std::runtime_error(path + ": material " + std::to_string(m) + " has an uncompressed embedded texture (only image files are read)");
      const uint8_t* p = reinterpret_cast<const uint8_t*>(emb->pcData);
      t.embedded.assign(p, p + emb->mWidth);
      t.file = t.name;
      t.bytes = emb->mWidth;
    } else {
      const std::string resolved = confined_path(root, t.name);
      if (resolved.empty() && !root.empty())
        throw std::runtime_error(path + ": material " + std::to_string(m) + " names texture '" + t.name +
                                 "', which is not in the scene's folder (only files beside the scene or below it are read)");
      if (!resolved.empty() && std::filesystem::is_regular_file(resolved, ec)) {
        t.file = resolved;
        t.bytes = std::filesystem::file_size(resolved, ec);
      }
    }
    texture_of[m] = static_cast<int>(s.textures.size());
    s.textures.push_back(std::move(t));
  }
  for (unsigned mi = 0; mi < as->mNumMeshes; ++mi) {
    const aiMesh* am = as->mMeshes[mi];
    const uint32_t base = static_cast<uint32_t>(s.vertices.size());
    const unsigned mat = am->mMaterialIndex < as->mNumMaterials ? am->mMaterialIndex : 0;
    for (unsigned i = 0; i < am->mNumVertices; ++i) {
      SceneVertex v;
      const aiVector3D& p = am->mVertices[i];
      if (!std::isfinite(p.x) || !std::isfinite(p.y) || !std::isfinite(p.z))
        throw std::runtime_error(path + ": mesh " + std::to_string(mi) + " vertex " + std::to_string(i) + " is not finite");
      v.pos = {p.x, -p.z, p.y};
      if (am->HasTextureCoords(0)) v.uv = {am->mTextureCoords[0][i].x, am->mTextureCoords[0][i].y};
      if (am->HasNormals()) v.normal = {am->mNormals[i].x, -am->mNormals[i].z, am->mNormals[i].y};
      if (am->HasVertexColors(0)) {
        const aiColor4D& c = am->mColors[0][i];
        v.color = {unit_to_byte(c.r), unit_to_byte(c.g), unit_to_byte(c.b), unit_to_byte(c.a)};
      } else {
        v.color = as->mNumMaterials > 0 ? colour[mat] : std::array<uint8_t, 4>{255, 255, 255, 255};
      }
      s.vertices.push_back(v);
    }
    SceneSurface f;
    f.texture = as->mNumMaterials > 0 ? texture_of[mat] : -1;
    f.first_index = static_cast<uint32_t>(s.indices.size());
    for (unsigned k = 0; k < am->mNumFaces; ++k) {
      const aiFace& face = am->mFaces[k];
      if (face.mNumIndices != 3) continue;
      for (int c = 0; c < 3; ++c) s.indices.push_back(base + face.mIndices[c]);
    }
    f.index_count = static_cast<uint32_t>(s.indices.size()) - f.first_index;
    ++s.meshes;
    if (f.index_count > 0) s.surfaces.push_back(f);
  }
  if (s.indices.empty()) throw std::runtime_error(path + ": holds no triangles");
  s.min = s.max = s.vertices[0].pos;
  for (const SceneVertex& v : s.vertices)
    for (int k = 0; k < 3; ++k) s.min[k] = std::min(s.min[k], v.pos[k]), s.max[k] = std::max(s.max[k], v.pos[k]);
  return s;
}

}  // namespace

Scene load_model_scene(const std::string& path) {
  const std::vector<uint8_t> bytes = read_file(path);
  std::error_code ec;
  const std::filesystem::path root = std::filesystem::weakly_canonical(std::filesystem::absolute(path), ec).parent_path();
  if (ec) throw std::runtime_error(path + ": cannot resolve its folder (" + ec.message() + ")");
  return read_scene(bytes.data(), bytes.size(), path, root);
}

Scene read_model_scene(const uint8_t* data, size_t size, const std::string& name) {
  return read_scene(data, size, name, std::filesystem::path());
}

}  // namespace vds::enc
