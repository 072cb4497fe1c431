// vds encoder: textured models through assimp, and their conversion to mesh
// colors (the rules are in vds/enc/mesh_colors.h).
#include <stdlib.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <map>
#include <stdexcept>

#include <assimp/material.h>
#include <assimp/postprocess.h>

#include "assimp_read.h"
#include "mesh_md3_check.h"
#include "text.h"
#include "vds/enc/mesh_colors.h"
#include "vds/enc/scene.h"
#include "vds/enc/stream_writer.h"
#include "vds/mesh_colors.h"

namespace vds::enc {
namespace {

Image read_texture(const aiScene* as, const std::string& path, const std::filesystem::path& root, unsigned m,
                   const std::string& named_file, std::string* where) {
  if (const aiTexture* emb = as->GetEmbeddedTexture(named_file.c_str())) {
    if (emb->mHeight != 0)
      throw std::runtime_error(path + ": material " + std::to_string(m) +
                               " has an uncompressed embedded texture (only image files are read)");
    *where = path + ":" + named_file;
    try {
      return decode_image(reinterpret_cast<const uint8_t*>(emb->pcData), emb->mWidth, *where, 3);
    } catch (const std::runtime_error& e) {
      throw std::runtime_error(path + ": material " + std::to_string(m) + "'s embedded texture: " + e.what());
    }
  }
  // Windows paths (an MS3D's ".\jeep1.jpg") name the same file with '/'.
  std::string file = named_file;
  std::replace(file.begin(), file.end(), '\\', '/');
  // A name assimp made up for a model that names no image ("$texture_dummy.bmp"
  // for an MD2 without skins) is the model's own name with an image's
  // extension, as such models ship (sydney.md2 beside sydney.bmp).
  if (!file.empty() && file[0] == '$') file = std::filesystem::path(path).stem().string() + ".png";
  std::string resolved = root.empty() ? std::string() : confined_path(root, file);
  if (root.empty())
    throw std::runtime_error(path + ": material " + std::to_string(m) + " names texture '" + file +
                             "', a separate file (a model read from memory may open none)");
  if (resolved.empty())
    throw std::runtime_error(path + ": material " + std::to_string(m) + " names texture '" + file +
                             "', which is not in the model's folder (only files beside the model or below it are read)");
  std::error_code ec;
  if (!std::filesystem::is_regular_file(resolved, ec)) {
    // Models often name a texture by another path, case or image format
    // than the file has: the same name in the model's folder is taken, else
    // the same name with another image extension (PNG, JPEG, TGA, BMP, in that order).
    const std::filesystem::path named(file);
    const std::string leaf = ascii_lower(named.filename().string()), stem = ascii_lower(named.stem().string());
    resolved.clear();
    std::string other;
    int other_rank = 99;
    for (const auto& entry : std::filesystem::directory_iterator(root, ec)) {
      const std::string have = ascii_lower(entry.path().filename().string());
      if (have == leaf) resolved = entry.path().string();
      const std::string ext = extension_of(have);
      const int rank = ext == "png" ? 0 : (ext == "jpg" || ext == "jpeg") ? 1 : ext == "tga" ? 2 : ext == "bmp" ? 3 : 99;
      if (rank < other_rank && ascii_lower(entry.path().stem().string()) == stem) {
        other = entry.path().string();
        other_rank = rank;
      }
    }
    if (resolved.empty()) resolved = other;
    if (resolved.empty() && file != named_file && named_file[0] == '$')
      throw std::runtime_error(path + ": material " + std::to_string(m) +
                               " names no image, and no image beside the model has its name (PNG, JPEG, TGA or BMP)");
    if (resolved.empty())
      throw std::runtime_error(path + ": material " + std::to_string(m) + " names texture '" + named_file +
                               "', which does not exist");
  }
  *where = resolved;
  try {
    return load_image(resolved, 3);
  } catch (const std::runtime_error& e) {
    throw std::runtime_error(path + ": material " + std::to_string(m) + "'s texture: " + e.what());
  }
}

TexturedModel read_model(const uint8_t* data, size_t size, const std::string& path, const std::filesystem::path& root) {
  if (size == 0) throw std::runtime_error(path + ": the file is empty");
  Assimp::Importer importer;
  importer.SetPropertyInteger(AI_CONFIG_PP_RVC_FLAGS, aiComponent_TANGENTS_AND_BITANGENTS | aiComponent_BONEWEIGHTS |
                                                          aiComponent_ANIMATIONS | aiComponent_LIGHTS |
                                                          aiComponent_CAMERAS | aiComponent_NORMALS);
  const unsigned steps = aiProcess_ValidateDataStructure | aiProcess_Triangulate | aiProcess_PreTransformVertices |
                         aiProcess_RemoveComponent;
  const aiScene* as = read_with_assimp(importer, data, size, path, extension_of(path), root, steps);
  TexturedModel t;
  t.name = path;
  std::map<std::string, int> texture_of_file;
  for (unsigned m = 0; m < as->mNumMaterials; ++m) {
    const aiMaterial* mat = as->mMaterials[m];
    TexturedMaterial tm;
    aiColor4D c;
    if (mat->Get(AI_MATKEY_BASE_COLOR, c) == aiReturn_SUCCESS || mat->Get(AI_MATKEY_COLOR_DIFFUSE, c) == aiReturn_SUCCESS)
      tm.colour = {std::clamp<double>(c.r, 0, 1), std::clamp<double>(c.g, 0, 1), std::clamp<double>(c.b, 0, 1)};
    aiString file;
    // A texture of no name (IQM's empty material) is none.
    if ((mat->GetTexture(aiTextureType_BASE_COLOR, 0, &file) == aiReturn_SUCCESS ||
         mat->GetTexture(aiTextureType_DIFFUSE, 0, &file) == aiReturn_SUCCESS) &&
        file.length > 0) {
      const std::string name = file.C_Str();
      auto it = texture_of_file.find(name);
      if (it == texture_of_file.end()) {
        std::string where;
        t.textures.push_back(read_texture(as, path, root, m, name, &where));
        t.texture_files.push_back(where);
        it = texture_of_file.emplace(name, static_cast<int>(t.textures.size()) - 1).first;
      }
      tm.texture = it->second;
      // A textured material's colour is often a placeholder for the
      // texture (assimp's default grey): only glTF's base colour factor scales it.
      if (mat->Get(AI_MATKEY_BASE_COLOR, c) != aiReturn_SUCCESS) tm.colour = {1, 1, 1};
    }
    t.materials.push_back(tm);
  }
  if (t.materials.empty()) t.materials.push_back(TexturedMaterial{});
  // Welding: bit-identical positions are one vertex (0.0 and -0.0 alike).
  std::map<std::array<double, 3>, uint32_t> index_of;
  for (unsigned mi = 0; mi < as->mNumMeshes; ++mi) {
    const aiMesh* am = as->mMeshes[mi];
    std::vector<uint32_t> welded(am->mNumVertices);
    for (unsigned i = 0; i < am->mNumVertices; ++i) {
      const aiVector3D& p = am->mVertices[i];
      if (!std::isfinite(p.x) || !std::isfinite(p.y) || !std::isfinite(p.z))
        throw std::runtime_error(path + ": mesh " + std::to_string(mi) + " vertex " + std::to_string(i) +
                                 " is not finite");
      const std::array<double, 3> key{p.x + 0.0, p.y + 0.0, p.z + 0.0};
      auto it = index_of.emplace(key, static_cast<uint32_t>(t.positions.size())).first;
      if (it->second == t.positions.size()) t.positions.push_back(key);
      welded[i] = it->second;
    }
    const int mat = am->mMaterialIndex < t.materials.size() ? static_cast<int>(am->mMaterialIndex) : 0;
    for (unsigned k = 0; k < am->mNumFaces; ++k) {
      const aiFace& face = am->mFaces[k];
      if (face.mNumIndices != 3) continue;
      std::array<uint32_t, 3> tri{};
      std::array<std::array<double, 2>, 3> uv{};
      std::array<std::array<double, 3>, 3> col{};
      for (int c = 0; c < 3; ++c) {
        const unsigned v = face.mIndices[c];
        tri[c] = welded[v];
        if (am->HasTextureCoords(0)) uv[c] = {am->mTextureCoords[0][v].x, am->mTextureCoords[0][v].y};
        if (!std::isfinite(uv[c][0]) || !std::isfinite(uv[c][1])) uv[c] = {0, 0};
        // Coordinates repeat with period 1; beyond a million their
        // fractions are noise anyway, so they are reduced.
        for (double& x : uv[c])
          if (std::fabs(x) > 1e6) x = std::fmod(x, 1.0);
        col[c] = {1, 1, 1};
        if (am->HasVertexColors(0)) {
          const aiColor4D& vc = am->mColors[0][v];
          col[c] = {std::clamp<double>(vc.r, 0, 1), std::clamp<double>(vc.g, 0, 1), std::clamp<double>(vc.b, 0, 1)};
        }
      }
      if (tri[0] == tri[1] || tri[1] == tri[2] || tri[0] == tri[2]) {
        ++t.dropped_faces;
        continue;
      }
      t.triangles.push_back(tri);
      t.uv.push_back(am->HasTextureCoords(0) ? uv : std::array<std::array<double, 2>, 3>{});
      t.colour.push_back(col);
      t.material.push_back(am->HasTextureCoords(0) ? mat : -1 - mat);
    }
  }
  // A face without texture coordinates keeps its material's colour only.
  for (int& m : t.material)
    if (m < 0) {
      const TexturedMaterial base = t.materials[static_cast<size_t>(-1 - m)];
      if (base.texture < 0) {
        m = -1 - m;
      } else {
        t.materials.push_back(TexturedMaterial{-1, base.colour});
        m = static_cast<int>(t.materials.size()) - 1;
      }
    }
  if (t.triangles.empty()) throw std::runtime_error(path + ": holds no triangles");
  return t;
}

TexturedModel load_model_file(const std::string& path) {
  const std::vector<uint8_t> bytes = read_file(path);
  std::error_code ec;
  const std::filesystem::path root = std::filesystem::weakly_canonical(std::filesystem::absolute(path), ec).parent_path();
  if (ec) throw std::runtime_error(path + ": cannot resolve its folder (" + ec.message() + ")");
  return read_model(bytes.data(), bytes.size(), path, root);
}

// --- Quake III players ------------------------------------------------------------------
//
// A player is three MD3 parts in one folder, each with its skin: the legs
// (lower.md3), the torso (upper.md3) placed on the legs' tag_torso, the
// head (head.md3) placed on the torso's tag_head, all at frame 0 (the game
// does the same with the frames of an animation). assimp turns an MD3's Z
// up into Y up, (x, y, z) -> (x, z, -y): a tag, in the file's axes, is
// applied between the two turns.

constexpr const char* kPlayerParts[3] = {"lower", "upper", "head"};

bool is_player_folder(const std::filesystem::path& dir) {
  std::error_code ec;
  for (const char* part : kPlayerParts)
    if (!std::filesystem::is_regular_file(dir / (std::string(part) + ".md3"), ec)) return false;
  return true;
}

Md3Tag part_tag(const std::filesystem::path& file, const char* tag) {
  const std::vector<uint8_t> bytes = read_file(file.string());
  check_md3(bytes.data(), bytes.size(), file.string());
  Md3Tag t;
  if (!md3_tag(bytes.data(), bytes.size(), file.string(), tag, 0, &t))
    throw std::runtime_error(file.string() + ": has no " + tag + " to join the player's next part to");
  return t;
}

// `part` placed by `tags` (the outermost first) and appended to `into`.
void append_part(TexturedModel& into, const TexturedModel& part, const std::vector<Md3Tag>& tags) {
  const uint32_t base = static_cast<uint32_t>(into.positions.size());
  const int materials = static_cast<int>(into.materials.size()), textures = static_cast<int>(into.textures.size());
  for (const std::array<double, 3>& a : part.positions) {
    std::array<double, 3> q = {a[0], -a[2], a[1]};  // back to the file's axes
    for (size_t k = tags.size(); k-- > 0;) {
      const Md3Tag& t = tags[k];
      std::array<double, 3> p = t.origin;
      for (int c = 0; c < 3; ++c) p[c] += q[0] * t.axis[0][c] + q[1] * t.axis[1][c] + q[2] * t.axis[2][c];
      q = p;
    }
    into.positions.push_back({q[0], q[2], -q[1]});
  }
  for (const std::array<uint32_t, 3>& t : part.triangles) into.triangles.push_back({t[0] + base, t[1] + base, t[2] + base});
  into.uv.insert(into.uv.end(), part.uv.begin(), part.uv.end());
  into.colour.insert(into.colour.end(), part.colour.begin(), part.colour.end());
  for (int m : part.material) into.material.push_back(m + materials);
  for (TexturedMaterial m : part.materials) {
    if (m.texture >= 0) m.texture += textures;
    into.materials.push_back(m);
  }
  into.textures.insert(into.textures.end(), part.textures.begin(), part.textures.end());
  into.texture_files.insert(into.texture_files.end(), part.texture_files.begin(), part.texture_files.end());
  into.dropped_faces += part.dropped_faces;
}

TexturedModel load_player(const std::filesystem::path& dir, const std::string& name) {
  TexturedModel t;
  t.name = name;
  const Md3Tag torso = part_tag(dir / "lower.md3", "tag_torso"), head = part_tag(dir / "upper.md3", "tag_head");
  append_part(t, load_model_file((dir / "lower.md3").string()), {});
  append_part(t, load_model_file((dir / "upper.md3").string()), {torso});
  append_part(t, load_model_file((dir / "head.md3").string()), {torso, head});
  if (t.positions.size() > mc::kMaxVertices)
    throw std::runtime_error(name + ": the player's three parts hold " + std::to_string(t.positions.size()) + " vertices");
  return t;
}

// A player's folder inside a .pk3 archive ("ARCHIVE.pk3:models/players/NAME"):
// the files directly in it (each at most 64 MiB, 256 MiB in all) copied to
// a private temporary folder, read as a player, and the folder removed.
TexturedModel load_player_from_archive(const std::string& archive, std::string folder, const std::string& name) {
  while (!folder.empty() && folder.back() == '/') folder.pop_back();
  const Pk3Set pk3(archive);
  const std::string prefix = ascii_lower(folder) + "/";
  std::vector<std::string> files;
  for (const std::string& e : pk3.entries(prefix, ""))
    if (e.size() > prefix.size() && e.find('/', prefix.size()) == std::string::npos && e.substr(prefix.size()) != "." &&
        e.substr(prefix.size()) != "..")
      files.push_back(e);
  if (files.empty()) throw std::runtime_error(name + ": the archive has no folder '" + folder + "'");
  std::string dir_template = (std::filesystem::temp_directory_path() / "vds-player-XXXXXX").string();
  if (mkdtemp(dir_template.data()) == nullptr) throw std::runtime_error(name + ": cannot make a temporary folder");
  const std::filesystem::path dir(dir_template);
  struct Remove {
    std::filesystem::path p;
    ~Remove() {
      std::error_code ec;
      std::filesystem::remove_all(p, ec);
    }
  } remove{dir};
  uint64_t total = 0;
  for (const std::string& e : files) {
    std::vector<uint8_t> bytes;
    pk3.read(e, &bytes);
    total += bytes.size();
    if (total > (uint64_t{256} << 20)) throw std::runtime_error(name + ": the folder's files come to over 256 MiB");
    write_file((dir / e.substr(prefix.size())).string(), bytes);
  }
  if (!is_player_folder(dir))
    throw std::runtime_error(name + ": the folder does not hold a player's lower.md3, upper.md3 and head.md3");
  TexturedModel t = load_player(dir, name);
  for (std::string& f : t.texture_files) f = archive + ":" + folder + "/" + std::filesystem::path(f).filename().string();
  return t;
}

}  // namespace

TexturedModel load_textured_model(const std::string& path) {
  const size_t pk3 = ascii_lower(path).find(".pk3:");
  if (pk3 != std::string::npos) return load_player_from_archive(path.substr(0, pk3 + 4), path.substr(pk3 + 5), path);
  std::error_code ec;
  if (std::filesystem::is_directory(path, ec)) {
    if (!is_player_folder(path))
      throw std::runtime_error(path + ": a folder is read as a Quake III player, and this one does not hold lower.md3, "
                               "upper.md3 and head.md3");
    return load_player(path, path);
  }
  return load_model_file(path);
}

TexturedModel read_textured_model(const uint8_t* data, size_t size, const std::string& name) {
  return read_model(data, size, name, std::filesystem::path());
}

double density_for_quality(double quality) {
  return std::clamp(0.5 / std::sqrt(std::max(quality, 1e-6)), 0.25, 1.0);
}

std::array<uint8_t, 3> rgb_to_ycc(double r, double g, double b) {
  const double y = 0.299 * r + 0.587 * g + 0.114 * b;
  const double cb = (b - y) * 0.5643 + 128, cr = (r - y) * 0.7132 + 128;
  auto byte = [](double v) { return static_cast<uint8_t>(std::lround(std::clamp(v, 0.0, 255.0))); };
  return {byte(y), byte(cb), byte(cr)};
}

namespace {

// A texture as a box-filtered pyramid (8-bit levels, as large as the
// image again at most), sampled trilinearly with repeating coordinates.
class Pyramid {
 public:
  explicit Pyramid(const Image& img) {
    levels_.push_back(img);
    while (levels_.back().width > 1 || levels_.back().height > 1) levels_.push_back(io::halve(levels_.back()));
  }
  int width() const { return levels_[0].width; }
  int height() const { return levels_[0].height; }

  // Colour (0..255) at (u, v) (v up), for samples `spacing` texels apart.
  std::array<double, 3> sample(double u, double v, double spacing) const {
    const double lod = std::clamp(std::log2(std::max(spacing, 1.0)), 0.0, static_cast<double>(levels_.size() - 1));
    const int l0 = static_cast<int>(lod);
    const int l1 = std::min(l0 + 1, static_cast<int>(levels_.size()) - 1);
    const double f = lod - l0;
    std::array<double, 3> a = at(levels_[l0], u, v), b = at(levels_[l1], u, v);
    for (int c = 0; c < 3; ++c) a[c] = a[c] * (1 - f) + b[c] * f;
    return a;
  }

 private:
  static std::array<double, 3> at(const Image& l, double u, double v) {
    return io::bilinear_repeat(l, u * l.width, (1 - v) * l.height);
  }
  std::vector<Image> levels_;
};

struct Accum {
  std::vector<double> sum;  // RGB per sample
  std::vector<uint32_t> count;
  void reset(uint32_t n) {
    sum.assign(3 * static_cast<size_t>(n), 0);
    count.assign(n, 0);
  }
  void add(uint32_t i, const std::array<double, 3>& c) {
    for (int k = 0; k < 3; ++k) sum[3 * static_cast<size_t>(i) + k] += c[k];
    ++count[i];
  }
};

}  // namespace

std::vector<std::vector<double>> coarser_face_sse(const MeshColorsModel& model) {
  const uint32_t F = static_cast<uint32_t>(model.face_res.size());
  const uint32_t V = static_cast<uint32_t>(model.positions.size());
  std::vector<uint8_t> work0(mc::MeshColors::init_bytes(F, V)), workk(work0.size());
  Arena arena0(work0.data(), work0.size()), arenak(workk.data(), workk.size());
  mc::MeshColors l0, lk;
  if (l0.init(arena0, model.triangles.data(), F, V) != Status::ok ||
      lk.init(arenak, model.triangles.data(), F, V) != Status::ok ||
      l0.set(model.face_res.data(), nullptr, 256) != Status::ok || lk.set(model.face_res.data(), nullptr, 256) != Status::ok)
    throw std::logic_error("mesh colors: layout set-up failed");
  std::vector<std::vector<double>> out(F);
  for (uint32_t f = 0; f < F; ++f) out[f].assign(static_cast<size_t>(model.face_res[f]) + 1, 0.0);
  l0.layout_level(0);
  const auto& p0 = model.levels[0];
  for (int k = 1; k <= model.max_res; ++k) {
    lk.layout_level(k);
    const auto& pk = model.levels[static_cast<size_t>(k)];
    for (uint32_t f = 0; f < F; ++f) {
      if (model.face_res[f] < k) continue;
      const uint32_t R = mc::resolution(model.face_res[f]);
      double sum = 0;
      for (uint32_t j = 1; j + 1 < R; ++j)
        for (uint32_t i = 1; i + j < R; ++i) {
          // The point in level k's lattice units and the lattice triangle
          // holding it (inside the face: i0 + j0 < R >> k).
          const double u = std::ldexp(static_cast<double>(i), -k), v = std::ldexp(static_cast<double>(j), -k);
          const uint32_t i0 = static_cast<uint32_t>(u), j0 = static_cast<uint32_t>(v);
          const double fu = u - i0, fv = v - j0;
          uint32_t a[3][2];
          double w[3];
          if (fu + fv <= 1) {
            a[0][0] = i0, a[0][1] = j0, a[1][0] = i0 + 1, a[1][1] = j0, a[2][0] = i0, a[2][1] = j0 + 1;
            w[0] = 1 - fu - fv, w[1] = fu, w[2] = fv;
          } else {
            a[0][0] = i0 + 1, a[0][1] = j0 + 1, a[1][0] = i0, a[1][1] = j0 + 1, a[2][0] = i0 + 1, a[2][1] = j0;
            w[0] = fu + fv - 1, w[1] = 1 - fu, w[2] = 1 - fv;
          }
          const uint32_t s = l0.sample_index(f, 0, i, j);
          for (int c = 0; c < 3; ++c) {
            double pred = 0;
            for (int t = 0; t < 3; ++t)
              if (w[t] != 0) pred += w[t] * pk[c][lk.sample_index(f, k, a[t][0], a[t][1])];
            const double d = p0[c][s] - pred;
            sum += kComponentWeight[c] * d * d;
          }
        }
      out[f][static_cast<size_t>(k)] = sum;
    }
  }
  return out;
}

MeshColorsModel to_mesh_colors(const TexturedModel& model, const MeshColorsOptions& o) {
  if (model.positions.size() > mc::kMaxVertices)
    throw std::runtime_error(model.name + ": " + std::to_string(model.positions.size()) +
                             " vertices; a client holds at most " + std::to_string(mc::kMaxVertices));
  if (model.triangles.size() > mc::kMaxFaces)
    throw std::runtime_error(model.name + ": " + std::to_string(model.triangles.size()) +
                             " faces; a client holds at most " + std::to_string(mc::kMaxFaces));
  const int max_allowed = std::clamp(o.max_res_log2, 0, mc::kMaxResLog2);
  MeshColorsModel out;
  out.positions = model.positions;
  const uint32_t F = static_cast<uint32_t>(model.triangles.size());
  const uint32_t V = static_cast<uint32_t>(model.positions.size());
  for (const auto& t : model.triangles)
    for (uint32_t v : t) out.triangles.push_back(static_cast<uint16_t>(v));
  std::vector<Pyramid> pyramids;
  for (const Image& img : model.textures) pyramids.emplace_back(img);

  // Each face's texel footprint: sqrt(2 A), A its area in texels.
  std::vector<double> extent(F, 0);
  out.face_res.assign(F, 0);
  for (uint32_t f = 0; f < F; ++f) {
    const TexturedMaterial& mat = model.materials[static_cast<size_t>(model.material[f])];
    if (mat.texture < 0) continue;
    const Pyramid& p = pyramids[static_cast<size_t>(mat.texture)];
    const auto& uv = model.uv[f];
    const double ux = (uv[1][0] - uv[0][0]) * p.width(), uy = (uv[1][1] - uv[0][1]) * p.height();
    const double vx = (uv[2][0] - uv[0][0]) * p.width(), vy = (uv[2][1] - uv[0][1]) * p.height();
    const double area = 0.5 * std::fabs(ux * vy - uy * vx);
    extent[f] = std::sqrt(2 * area);
    const double want = o.density * extent[f];
    int r = std::clamp(o.min_res_log2, 0, max_allowed);
    while (r < max_allowed && static_cast<double>(1u << r) < want) ++r;
    out.face_res[f] = static_cast<uint8_t>(r);
    out.max_res = std::max(out.max_res, r);
  }
  // A face without a texture next to textured ones (a window in a painted
  // body) keeps its own colour inside and the texture's on the shared
  // vertices and edges: it gets the samples per unit of surface its
  // textured neighbours have, so the change of colour is as sharp as the
  // texture beside it.
  auto world_extent = [&](uint32_t f) {
    const auto& a = model.positions[model.triangles[f][0]];
    const auto& b = model.positions[model.triangles[f][1]];
    const auto& c = model.positions[model.triangles[f][2]];
    const double ux = b[0] - a[0], uy = b[1] - a[1], uz = b[2] - a[2];
    const double vx = c[0] - a[0], vy = c[1] - a[1], vz = c[2] - a[2];
    const double cx = uy * vz - uz * vy, cy = uz * vx - ux * vz, cz = ux * vy - uy * vx;
    return std::sqrt(std::sqrt(cx * cx + cy * cy + cz * cz));  // sqrt(2 x area)
  };
  std::vector<double> density(V, 0);  // samples per unit of length round each vertex
  for (uint32_t f = 0; f < F; ++f) {
    if (model.materials[static_cast<size_t>(model.material[f])].texture < 0) continue;
    const double we = world_extent(f);
    if (!(we > 0)) continue;
    for (uint32_t v : model.triangles[f]) density[v] = std::max(density[v], mc::resolution(out.face_res[f]) / we);
  }
  // Untextured faces of different colours meeting at a vertex (glass in a
  // trim) need samples inside too: where no textured face is near, the
  // model's median textured density.
  std::vector<double> densities;
  for (double d : density)
    if (d > 0) densities.push_back(d);
  std::sort(densities.begin(), densities.end());
  const double median = densities.empty() ? 0 : densities[densities.size() / 2];
  auto face_colour = [&](uint32_t f) {
    const TexturedMaterial& mat = model.materials[static_cast<size_t>(model.material[f])];
    std::array<double, 3> c{};
    for (int k = 0; k < 3; ++k)
      c[k] = mat.colour[k] * (model.colour[f][0][k] + model.colour[f][1][k] + model.colour[f][2][k]) / 3;
    return c;
  };
  std::vector<std::array<double, 3>> vertex_colour(V, {-1, -1, -1});
  std::vector<uint8_t> conflict(V, 0);
  for (uint32_t f = 0; f < F; ++f) {
    if (model.materials[static_cast<size_t>(model.material[f])].texture >= 0) continue;
    const auto c = face_colour(f);
    for (uint32_t v : model.triangles[f]) {
      if (vertex_colour[v][0] < 0) vertex_colour[v] = c;
      for (int k = 0; k < 3; ++k) conflict[v] |= std::fabs(vertex_colour[v][k] - c[k]) > 1.0 / 255;
    }
  }
  for (uint32_t f = 0; f < F; ++f) {
    if (model.materials[static_cast<size_t>(model.material[f])].texture >= 0) continue;
    double d = 0;
    for (uint32_t v : model.triangles[f]) d = std::max(d, conflict[v] ? std::max(density[v], median) : density[v]);
    const double want = d * world_extent(f);
    int r = 0;
    while (r < max_allowed && static_cast<double>(1u << r) < want) ++r;
    out.face_res[f] = static_cast<uint8_t>(r);
    out.max_res = std::max(out.max_res, r);
  }

  std::vector<uint8_t> work(mc::MeshColors::init_bytes(F, V));
  Arena arena(work.data(), work.size());
  mc::MeshColors layout;
  if (layout.init(arena, out.triangles.data(), F, V) != Status::ok)
    throw std::logic_error("mesh colors: layout set-up failed");
  const mc::Topology& topo = layout.topology();

  // A face's colour at barycentric weights w for samples `spacing` texels apart.
  auto colour_at = [&](uint32_t f, const std::array<double, 3>& w, double spacing) {
    const TexturedMaterial& mat = model.materials[static_cast<size_t>(model.material[f])];
    std::array<double, 3> c{255, 255, 255};
    if (mat.texture >= 0) {
      const auto& uv = model.uv[f];
      const double u = w[0] * uv[0][0] + w[1] * uv[1][0] + w[2] * uv[2][0];
      const double v = w[0] * uv[0][1] + w[1] * uv[1][1] + w[2] * uv[2][1];
      c = pyramids[static_cast<size_t>(mat.texture)].sample(u, v, spacing);
    }
    for (int k = 0; k < 3; ++k) {
      const double vc = w[0] * model.colour[f][0][k] + w[1] * model.colour[f][1][k] + w[2] * model.colour[f][2][k];
      c[k] *= mat.colour[k] * vc;
    }
    return c;
  };
  // A seam of the map where the two sides' colours differ (islands painted
  // apart) is one row of averaged samples: the faces on it get twice the
  // resolution, so that row is half as wide.
  auto textured = [&](uint32_t f) { return model.materials[static_cast<size_t>(model.material[f])].texture >= 0; };
  if (o.seam_boost) {
    std::vector<std::array<int64_t, 2>> sides(topo.edges, {-1, -1});
    std::vector<uint8_t> many(topo.edges, 0);
    for (uint32_t f = 0; f < F; ++f)
      for (int k = 0; k < 3; ++k) {
        const uint32_t e = topo.face_edge[3 * f + k] >> 1;
        if (sides[e][0] < 0)
          sides[e][0] = 3 * int64_t{f} + k;
        else if (sides[e][1] < 0)
          sides[e][1] = 3 * int64_t{f} + k;
        else
          many[e] = 1;
      }
    std::vector<uint8_t> boost(F, 0);
    for (uint32_t e = 0; e < topo.edges; ++e) {
      if (many[e] || sides[e][1] < 0) continue;
      const uint32_t f = static_cast<uint32_t>(sides[e][0] / 3), g = static_cast<uint32_t>(sides[e][1] / 3);
      const int kf = static_cast<int>(sides[e][0] % 3), kg = static_cast<int>(sides[e][1] % 3);
      if (!textured(f) || !textured(g)) continue;
      // Point t along the edge from its start: in f's corners kf -> kf+1 when f runs it forward.
      const bool f_rev = (topo.face_edge[3 * f + kf] & 1u) != 0, g_rev = (topo.face_edge[3 * g + kg] & 1u) != 0;
      double mismatch = 0;
      for (int i = 0; i < 8; ++i) {
        const double t = (i + 0.5) / 8;
        std::array<double, 3> wf{0, 0, 0}, wg{0, 0, 0};
        wf[kf] = f_rev ? t : 1 - t;
        wf[(kf + 1) % 3] = f_rev ? 1 - t : t;
        wg[kg] = g_rev ? t : 1 - t;
        wg[(kg + 1) % 3] = g_rev ? 1 - t : t;
        const auto a = colour_at(f, wf, extent[f] / mc::resolution(out.face_res[f]));
        const auto b = colour_at(g, wg, extent[g] / mc::resolution(out.face_res[g]));
        double d = 0;
        for (int c = 0; c < 3; ++c) d = std::max(d, std::fabs(a[c] - b[c]));
        mismatch += d / 8;
      }
      if (mismatch > 24) boost[f] = boost[g] = 1;
    }
    for (uint32_t f = 0; f < F; ++f)
      if (boost[f] && out.face_res[f] < max_allowed) out.max_res = std::max<int>(out.max_res, ++out.face_res[f]);
  }
  if (!o.face_max_res.empty()) {
    if (o.face_max_res.size() != F) throw std::invalid_argument("mesh colors: a resolution cap per face is needed");
    out.max_res = 0;
    for (uint32_t f = 0; f < F; ++f) {
      out.face_res[f] = std::min(out.face_res[f], o.face_max_res[f]);
      out.max_res = std::max<int>(out.max_res, out.face_res[f]);
    }
  }
  if (layout.set(out.face_res.data(), nullptr, 256) != Status::ok) throw std::logic_error("mesh colors: layout set-up failed");

  auto to_planes = [](const Accum& a, uint32_t from, uint32_t to, std::array<std::vector<uint8_t>, 3>& planes) {
    for (uint32_t i = from; i < to; ++i) {
      const double n = a.count[i] > 0 ? a.count[i] : 1;
      const auto ycc = rgb_to_ycc(a.sum[3 * i] / n, a.sum[3 * i + 1] / n, a.sum[3 * i + 2] / n);
      for (int c = 0; c < 3; ++c) planes[c][i] = ycc[c];
    }
  };

  // Where a textured face meets an untextured one, the textured face alone
  // gives the shared samples.
  std::vector<uint8_t> textured_vertex(V, 0), textured_edge(topo.edges, 0);
  for (uint32_t f = 0; f < F; ++f)
    if (textured(f))
      for (int k = 0; k < 3; ++k) {
        textured_vertex[out.triangles[3 * f + k]] = 1;
        textured_edge[topo.face_edge[3 * f + k] >> 1] = 1;
      }

  // Vertex samples: level 0's, the mean over the faces around.
  Accum acc;
  acc.reset(V);
  if (!o.vertex_filter_res.empty() && o.vertex_filter_res.size() != F)
    throw std::invalid_argument("mesh colors: a vertex filter resolution per face is needed");
  for (uint32_t f = 0; f < F; ++f) {
    const int filter_res = o.vertex_filter_res.empty() ? out.face_res[f] : std::min<int>(o.vertex_filter_res[f], mc::kMaxResLog2);
    const double spacing = extent[f] / mc::resolution(filter_res);
    for (int k = 0; k < 3; ++k) {
      if (!textured(f) && textured_vertex[out.triangles[3 * f + k]]) continue;
      std::array<double, 3> w{0, 0, 0};
      w[k] = 1;
      acc.add(out.triangles[3 * f + k], colour_at(f, w, spacing));
    }
  }
  std::array<std::vector<uint8_t>, 3> vplanes{std::vector<uint8_t>(V), std::vector<uint8_t>(V), std::vector<uint8_t>(V)};
  to_planes(acc, 0, V, vplanes);
  out.vertex_ycc.resize(3 * static_cast<size_t>(V));
  for (uint32_t v = 0; v < V; ++v)
    for (int c = 0; c < 3; ++c) out.vertex_ycc[3 * v + c] = vplanes[c][v];

  for (int m = 0; m <= out.max_res; ++m) {
    const uint32_t total = layout.layout_level(m);
    const mc::Layout& l = layout.layout();
    acc.reset(total);
    for (uint32_t f = 0; f < F; ++f) {
      const uint32_t R = mc::resolution(mc::level_res(out.face_res[f], m));
      // Edge samples at the edge's own resolution, through this face's coordinates.
      for (int k = 0; k < 3; ++k) {
        const uint32_t fe = topo.face_edge[3 * f + k], e = fe >> 1;
        if (!textured(f) && textured_edge[e]) continue;
        const uint32_t Re = mc::resolution(mc::level_res(layout.edge_res()[e], m));
        const double spacing = extent[f] / Re;
        for (uint32_t p = 1; p < Re; ++p) {
          const double t = static_cast<double>(p) / Re;
          std::array<double, 3> w{0, 0, 0};
          w[k] = 1 - t;
          w[(k + 1) % 3] = t;
          const uint32_t q = (fe & 1u) ? Re - p : p;
          acc.add(l.edge_base + l.edge_offset[e] + q - 1, colour_at(f, w, spacing));
        }
      }
      const double spacing = extent[f] / R;
      for (uint32_t j = 1; j + 1 < R; ++j)
        for (uint32_t i = 1; i + j < R; ++i) {
          const std::array<double, 3> w{static_cast<double>(R - i - j) / R, static_cast<double>(i) / R,
                                        static_cast<double>(j) / R};
          acc.add(layout.sample_index(f, m, i, j), colour_at(f, w, spacing));
        }
    }
    std::array<std::vector<uint8_t>, 3> planes{std::vector<uint8_t>(total), std::vector<uint8_t>(total),
                                               std::vector<uint8_t>(total)};
    for (uint32_t v = 0; v < V; ++v)
      for (int c = 0; c < 3; ++c) planes[c][v] = vplanes[c][v];
    to_planes(acc, V, total, planes);
    out.levels.push_back(std::move(planes));
  }
  return out;
}

}  // namespace vds::enc
