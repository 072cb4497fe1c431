// The shared scene description (vds/enc/scene.h): vector helpers, cameras,
// procedural textures, the standard scenes and their fixed-point client copy.
#include "vds/ref/scene.h"

#include <algorithm>
#include <cmath>
#include <cstring>
#include <stdexcept>

#include "vds/homography.h"

namespace vds::ref {

namespace {

constexpr double kPi = 3.14159265358979323846;

uint32_t hash32(uint32_t x, uint32_t y, uint32_t seed) {
  uint32_t h = x * 0x9E3779B1u ^ (y + 0x7F4A7C15u) * 0x85EBCA77u ^ seed * 0xC2B2AE3Du;
  h ^= h >> 15;
  h *= 0x2C1B3C6Du;
  h ^= h >> 12;
  h *= 0x297A2D39u;
  h ^= h >> 15;
  return h;
}
double hash01(uint32_t x, uint32_t y, uint32_t seed) { return (hash32(x, y, seed) & 0xFFFFFF) / double(0xFFFFFF); }

// Value noise on a lattice of period `period` cells (wraps, so it tiles).
double value_noise(double x, double y, int period, uint32_t seed) {
  const int xi = static_cast<int>(std::floor(x)), yi = static_cast<int>(std::floor(y));
  const double fx = x - xi, fy = y - yi;
  auto l = [&](int a, int b) {
    return hash01(static_cast<uint32_t>(((a % period) + period) % period), static_cast<uint32_t>(((b % period) + period) % period), seed);
  };
  const double sx = fx * fx * (3 - 2 * fx), sy = fy * fy * (3 - 2 * fy);
  const double top = l(xi, yi) + (l(xi + 1, yi) - l(xi, yi)) * sx;
  const double bot = l(xi, yi + 1) + (l(xi + 1, yi + 1) - l(xi, yi + 1)) * sx;
  return top + (bot - top) * sy;
}

TextureD texture(const std::string& name, Image image, TexAddress address = TexAddress::repeat) {
  TextureD t;
  t.name = name;
  t.image = std::move(image);
  t.address = address;
  return t;
}

uint8_t clamp8(double v) { return static_cast<uint8_t>(std::clamp(std::lround(v), 0L, 255L)); }

void put(Image& img, int x, int y, double r, double g, double b) {
  img.at(x, y, 0) = clamp8(r);
  img.at(x, y, 1) = clamp8(g);
  img.at(x, y, 2) = clamp8(b);
}

double ch(uint32_t c, int k) { return static_cast<double>((c >> (16 - 8 * k)) & 255); }

uint16_t pack565(uint32_t c) {
  const uint32_t r = (c >> 16) & 255, g = (c >> 8) & 255, b = c & 255;
  return static_cast<uint16_t>((((r * 249 + 1014) >> 11) << 11) | (((g * 253 + 505) >> 10) << 5) | ((b * 249 + 1014) >> 11));
}
uint32_t expand565(uint32_t c) {
  const uint32_t r = c >> 11, g = (c >> 5) & 63, b = c & 31;
  return ((r << 3 | r >> 2) << 16) | ((g << 2 | g >> 4) << 8) | (b << 3 | b >> 2);
}
uint32_t pixel(const Image& img, int x, int y) {
  return (uint32_t{img.at(x, y, 0)} << 16) | (uint32_t{img.at(x, y, 1)} << 8) | img.at(x, y, 2);
}

Mat3d rot_y(double a) {
  Mat3d m;
  m.m[0][0] = std::cos(a);
  m.m[0][2] = std::sin(a);
  m.m[2][0] = -std::sin(a);
  m.m[2][2] = std::cos(a);
  return m;
}
Mat3d rot_x(double a) {
  Mat3d m;
  m.m[1][1] = std::cos(a);
  m.m[1][2] = -std::sin(a);
  m.m[2][1] = std::sin(a);
  m.m[2][2] = std::cos(a);
  return m;
}

// A box as six quads, each its own mesh (so each face can be mapped from a
// view on its own). `proto` gives shading, texture and filter.
void add_box(Scene& s, Vec3d centre, Vec3d half, const Mat3d& rot, const MeshD& proto, int tex_size,
             const std::vector<uint32_t>& face_colors, const std::vector<int>& face_textures) {
  const Vec3d axes[3] = {{1, 0, 0}, {0, 1, 0}, {0, 0, 1}};
  // The eight corners, computed once: faces that share an edge must share
  // bit-identical positions (no cracks).
  Vec3d corners[8];
  for (int i = 0; i < 8; ++i) {
    const Vec3d local{(i & 1) ? half.x : -half.x, (i & 2) ? half.y : -half.y, (i & 4) ? half.z : -half.z};
    corners[i] = centre + rot * local;
  }
  auto corner_of = [&](const double s3[3]) {
    return corners[(s3[0] > 0 ? 1 : 0) | (s3[1] > 0 ? 2 : 0) | (s3[2] > 0 ? 4 : 0)];
  };
  for (int f = 0; f < 6; ++f) {
    const int a = f / 2;  // axis of the normal
    const double sgn = (f & 1) ? -1.0 : 1.0;
    const int b = (a + 1) % 3, c = (a + 2) % 3;
    Vec3d corner[4];
    const double sb[4] = {-1, 1, 1, -1}, sc[4] = {-1, -1, 1, 1};
    for (int k = 0; k < 4; ++k) {
      double s3[3];
      s3[a] = sgn;
      s3[b] = sb[k];
      s3[c] = sc[k];
      corner[k] = corner_of(s3);
    }
    const double t = tex_size;
    const Vec2d uv[4] = {{0, t}, {t, t}, {t, 0}, {0, 0}};
    MeshD m = proto;
    if (!face_colors.empty()) m.color = face_colors[static_cast<size_t>(f) % face_colors.size()];
    if (!face_textures.empty()) m.texture = face_textures[static_cast<size_t>(f) % face_textures.size()];
    uint32_t cols[4];
    for (int k = 0; k < 4; ++k) cols[k] = hash32(static_cast<uint32_t>(f), static_cast<uint32_t>(k), 77) | 0x404040u;
    s.add_quad(m, corner, uv, rot * (axes[a] * sgn), cols);
    s.meshes.push_back(m);
  }
}

}  // namespace

Vec3d normalize(Vec3d a) {
  const double l = std::sqrt(dot(a, a));
  return l > 0 ? a * (1.0 / l) : a;
}

Mat3d operator*(const Mat3d& a, const Mat3d& b) {
  Mat3d r;
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j) r.m[i][j] = a.m[i][0] * b.m[0][j] + a.m[i][1] * b.m[1][j] + a.m[i][2] * b.m[2][j];
  return r;
}
Vec3d operator*(const Mat3d& a, Vec3d v) {
  return {a.m[0][0] * v.x + a.m[0][1] * v.y + a.m[0][2] * v.z, a.m[1][0] * v.x + a.m[1][1] * v.y + a.m[1][2] * v.z,
          a.m[2][0] * v.x + a.m[2][1] * v.y + a.m[2][2] * v.z};
}
Mat3d transpose(const Mat3d& a) {
  Mat3d r;
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j) r.m[i][j] = a.m[j][i];
  return r;
}

CameraD CameraD::look_at(Vec3d eye, Vec3d target, Vec3d up, int width, int height, double fov_y_deg, double near_z,
                         double far_z) {
  CameraD c;
  const Vec3d f = normalize(target - eye);
  const Vec3d r = normalize(cross(f, up));
  const Vec3d d = cross(f, r);  // right x down = forward: right-handed, y down on screen
  c.rotation.m[0][0] = r.x, c.rotation.m[0][1] = r.y, c.rotation.m[0][2] = r.z;
  c.rotation.m[1][0] = d.x, c.rotation.m[1][1] = d.y, c.rotation.m[1][2] = d.z;
  c.rotation.m[2][0] = f.x, c.rotation.m[2][1] = f.y, c.rotation.m[2][2] = f.z;
  c.position = eye;
  c.fy = 0.5 * height / std::tan(0.5 * fov_y_deg * kPi / 180.0);
  c.fx = c.fy;
  c.cx = 0.5 * width;
  c.cy = 0.5 * height;
  c.near_z = near_z;
  c.far_z = far_z;
  return c;
}

CameraD CameraD::scaled(double s) const {
  CameraD c = *this;
  c.fx *= s;
  c.fy *= s;
  c.cx *= s;
  c.cy *= s;
  return c;
}

uint32_t Scene::add_vertex(Vec3d p, Vec2d uv, uint32_t color, Vec2d lightmap_uv) {
  positions.push_back(p);
  uvs.push_back(uv);
  colors.push_back(color);
  lightmap_uvs.push_back(lightmap_uv);
  return static_cast<uint32_t>(positions.size() - 1);
}

void Scene::add_quad(MeshD& mesh, const Vec3d p[4], const Vec2d uv[4], Vec3d outward, const uint32_t cols[4],
                     const Vec2d lm[4]) {
  uint32_t idx[4];
  for (int k = 0; k < 4; ++k) idx[k] = add_vertex(p[k], uv[k], cols ? cols[k] : 0, lm ? lm[k] : Vec2d{});
  // Front faces have (P1 - P0) x (P2 - P0) toward the viewer (vds/render.h).
  const bool keep = dot(cross(p[1] - p[0], p[2] - p[0]), outward) > 0;
  const uint32_t order[2][6] = {{0, 1, 2, 0, 2, 3}, {0, 2, 1, 0, 3, 2}};
  for (uint32_t k : order[keep ? 0 : 1]) mesh.indices.push_back(idx[k]);
}

// ---------------------------------------------------------------------------
// Procedural textures
// ---------------------------------------------------------------------------
Image make_checker_texture(int size, int cells, uint32_t a, uint32_t b) {
  Image img(size, size, 3);
  const int cell = std::max(1, size / cells);
  for (int y = 0; y < size; ++y)
    for (int x = 0; x < size; ++x) {
      const uint32_t c = ((x / cell + y / cell) & 1) ? b : a;
      const double n = 14 * (hash01(static_cast<uint32_t>(x), static_cast<uint32_t>(y), 5) - 0.5);
      put(img, x, y, ch(c, 0) + n, ch(c, 1) + n, ch(c, 2) + n);
    }
  return img;
}

Image make_brick_texture(int size) {
  Image img(size, size, 3);
  const int bh = size / 8, bw = size / 4;
  for (int y = 0; y < size; ++y)
    for (int x = 0; x < size; ++x) {
      const int row = y / bh;
      const int xs = x + ((row & 1) ? bw / 2 : 0);
      const int col = (xs / bw) % 4;
      const bool mortar = (y % bh) < 2 || (xs % bw) < 2;
      const double n = value_noise(x / 8.0, y / 8.0, size / 8, 11) * 40 - 20;
      if (mortar) {
        put(img, x, y, 190 + n * 0.3, 186 + n * 0.3, 176 + n * 0.3);
      } else {
        const double v = hash01(static_cast<uint32_t>(col), static_cast<uint32_t>(row), 3) * 50;
        put(img, x, y, 150 + v + n, 62 + v * 0.5 + n * 0.6, 44 + n * 0.4);
      }
    }
  return img;
}

Image make_tile_texture(int size) {
  Image img(size, size, 3);
  const int tile = size / 4;
  for (int y = 0; y < size; ++y)
    for (int x = 0; x < size; ++x) {
      const bool grout = (x % tile) < 2 || (y % tile) < 2;
      const double v = hash01(static_cast<uint32_t>(x / tile), static_cast<uint32_t>(y / tile), 9);
      const double n = value_noise(x / 4.0, y / 4.0, size / 4, 21) * 24 - 12;
      if (grout) {
        put(img, x, y, 70 + n, 70 + n, 75 + n);
      } else {
        put(img, x, y, 200 - 60 * v + n, 205 - 40 * v + n, 190 - 20 * v + n);
      }
    }
  return img;
}

Image make_noise_texture(int size, uint32_t seed, uint32_t dark, uint32_t light) {
  Image img(size, size, 3);
  for (int y = 0; y < size; ++y)
    for (int x = 0; x < size; ++x) {
      double t = 0, amp = 0.5;
      for (int o = 0, cells = 4; o < 4; ++o, cells *= 2, amp *= 0.5) {
        t += amp * value_noise(x * cells / double(size), y * cells / double(size), cells, seed + static_cast<uint32_t>(o));
      }
      t = std::clamp((t - 0.2) / 0.7, 0.0, 1.0);
      put(img, x, y, ch(dark, 0) + (ch(light, 0) - ch(dark, 0)) * t, ch(dark, 1) + (ch(light, 1) - ch(dark, 1)) * t,
          ch(dark, 2) + (ch(light, 2) - ch(dark, 2)) * t);
    }
  return img;
}

Image make_face_texture(int size, int face) {
  Image img(size, size, 3);
  static const uint32_t hues[6] = {0xD84A3A, 0x3A8FD8, 0x4AC058, 0xE0B030, 0x9A52C8, 0x30B8B0};
  const uint32_t base = hues[face % 6];
  for (int y = 0; y < size; ++y)
    for (int x = 0; x < size; ++x) {
      const double u = (x + 0.5) / size - 0.5, v = (y + 0.5) / size - 0.5;
      const double r = std::sqrt(u * u + v * v);
      const bool ring = std::fmod(r * 10.0 + face * 0.13, 1.0) < 0.35;
      const bool border = x < size / 16 || y < size / 16 || x >= size - size / 16 || y >= size - size / 16;
      const bool mark = u < -0.25 && v < -0.25 && ((x / (size / 32)) + (y / (size / 32))) % 2 == 0;  // orientation
      double k = ring ? 1.0 : 0.55;
      if (border) k = 0.25;
      if (mark) k = 1.3;
      const double n = 10 * (hash01(static_cast<uint32_t>(x), static_cast<uint32_t>(y), 100 + static_cast<uint32_t>(face)) - 0.5);
      put(img, x, y, ch(base, 0) * k + n, ch(base, 1) * k + n, ch(base, 2) * k + n);
    }
  return img;
}

// ---------------------------------------------------------------------------
// Standard scenes
// ---------------------------------------------------------------------------
Scene make_cube_scene(int width, int height) {
  Scene s;
  s.name = "cube";
  s.width = width;
  s.height = height;
  s.clear_color = 0x8CB4DC;
  for (int f = 0; f < 6; ++f) s.textures.push_back(texture("face" + std::to_string(f), make_face_texture(128, f)));
  s.textures.push_back(texture("checker", make_checker_texture(64, 8, 0xE8E4DA, 0x3C4650)));
  const int checker = 6;

  // The floor: 4 x 4 quads of 10 x 10 units, texture repeating every 4 units.
  MeshD floor;
  floor.shading = Shading::texture;
  floor.texture = checker;
  for (int i = 0; i < 4; ++i)
    for (int j = 0; j < 4; ++j) {
      const double x0 = -20 + 10 * i, z0 = -20 + 10 * j;
      const Vec3d p[4] = {{x0, 0, z0}, {x0 + 10, 0, z0}, {x0 + 10, 0, z0 + 10}, {x0, 0, z0 + 10}};
      Vec2d uv[4];
      for (int k = 0; k < 4; ++k) uv[k] = {(p[k].x + 20) * 16, (p[k].z + 20) * 16};
      s.add_quad(floor, p, uv, {0, 1, 0});
    }
  s.meshes.push_back(floor);

  // The textured cube, turned and tilted.
  MeshD proto;
  proto.shading = Shading::texture;
  add_box(s, {0, 1.15, 0}, {1, 1, 1}, rot_y(0.45) * rot_x(0.12), proto, 128, {}, {0, 1, 2, 3, 4, 5});

  // A Gouraud pyramid and a flat-shaded pillar.
  MeshD pyr;
  pyr.shading = Shading::gouraud;
  const Vec3d apex{2.7, 1.7, 0.9};
  const Vec3d base[4] = {{2.0, 0, 0.2}, {3.4, 0, 0.2}, {3.4, 0, 1.6}, {2.0, 0, 1.6}};
  const uint32_t cols[5] = {0xFF3030, 0x30FF30, 0x3030FF, 0xFFFF40, 0xFFFFFF};
  for (int k = 0; k < 4; ++k) {
    const Vec3d a = base[k], b = base[(k + 1) % 4];
    const uint32_t i0 = s.add_vertex(a, {}, cols[k]), i1 = s.add_vertex(b, {}, cols[(k + 1) % 4]),
                   i2 = s.add_vertex(apex, {}, cols[4]);
    const Vec3d out = cross(b - a, apex - a);
    const Vec3d centre{2.7, 0.5, 0.9};
    const bool keep = dot(out, a - centre) > 0;
    for (uint32_t i : keep ? std::vector<uint32_t>{i0, i1, i2} : std::vector<uint32_t>{i0, i2, i1}) pyr.indices.push_back(i);
  }
  s.meshes.push_back(pyr);
  MeshD pillar;
  pillar.shading = Shading::flat;
  add_box(s, {-2.6, 1.25, 1.8}, {0.35, 1.25, 0.35}, rot_y(0.2), pillar, 1, {0xC0A070, 0x907850, 0xA08860}, {});

  s.camera = CameraD::look_at({3.4, 2.7, -4.6}, {0.2, 0.9, 0.3}, {0, 1, 0}, width, height, 55, 0.5, 60);
  return s;
}

Scene make_terrain_scene(int width, int height) {
  Scene s;
  s.name = "terrain";
  s.width = width;
  s.height = height;
  s.clear_color = 0xA8C8E8;
  s.textures.push_back(texture("grass", make_noise_texture(128, 7, 0x2E5A1C, 0x9CB85A)));
  MeshD m;
  m.shading = Shading::texture;
  m.texture = 0;
  constexpr int kN = 32;
  auto height_at = [](double x, double z) { return 1.3 * std::sin(0.33 * x) * std::cos(0.29 * z) + 0.45 * std::sin(0.9 * x + 0.4 * z); };
  std::vector<uint32_t> grid;
  for (int j = 0; j <= kN; ++j)
    for (int i = 0; i <= kN; ++i) {
      const double x = i - kN / 2.0, z = j - kN / 2.0;
      grid.push_back(s.add_vertex({x, height_at(x, z), z}, {i * 32.0, j * 32.0}));
    }
  for (int j = 0; j < kN; ++j)
    for (int i = 0; i < kN; ++i) {
      const uint32_t a = grid[static_cast<size_t>(j * (kN + 1) + i)], b = a + 1, c = a + kN + 1, d = c + 1;
      // Up-facing: (P1 - P0) x (P2 - P0) has +y: a, c, b and b, c, d.
      for (uint32_t k : {a, c, b, b, c, d}) m.indices.push_back(k);
    }
  s.meshes.push_back(m);
  // Far plane inside the grid: the far corner is clipped away.
  s.camera = CameraD::look_at({-13, 5.5, -14}, {3, 0, 2}, {0, 1, 0}, width, height, 60, 0.2, 30);
  return s;
}

Scene make_room_scene(int width, int height) {
  Scene s;
  s.name = "room";
  s.width = width;
  s.height = height;
  s.clear_color = 0x000000;
  s.textures.push_back(texture("tiles", make_tile_texture(64)));
  s.textures.push_back(texture("bricks", make_brick_texture(128)));
  s.textures.push_back(texture("plaster", make_noise_texture(64, 31, 0xB8B0A0, 0xE8E2D6)));
  s.textures.push_back(texture("crate", make_checker_texture(32, 4, 0xB08040, 0x6A4820)));
  // A lightmap (reference renderer only): a soft pool of light.
  {
    Image lm(32, 32, 3);
    for (int y = 0; y < 32; ++y)
      for (int x = 0; x < 32; ++x) {
        const double d = std::hypot(x - 18.0, y - 14.0) / 22.0;
        const double v = 255 * std::clamp(1.0 - 0.75 * d * d, 0.2, 1.0);
        put(lm, x, y, v, v * 0.97, v * 0.9);
      }
    s.textures.push_back(texture("lightmap", lm, TexAddress::clamp));
  }
  constexpr double X = 4, Y = 3, Z = 3;
  auto wall = [&](int tex, double scale, Vec3d o, Vec3d du, Vec3d dv, Vec3d inward, int nu, int nv) {
    MeshD m;
    m.shading = Shading::texture;
    m.texture = tex;
    m.lightmap = 4;
    for (int j = 0; j < nv; ++j)
      for (int i = 0; i < nu; ++i) {
        Vec3d p[4];
        Vec2d uv[4], lm[4];
        const double a[4] = {0, 1, 1, 0}, b[4] = {0, 0, 1, 1};
        for (int k = 0; k < 4; ++k) {
          const double fu = (i + a[k]) / nu, fv = (j + b[k]) / nv;
          p[k] = o + du * fu + dv * fv;
          uv[k] = {fu * std::sqrt(dot(du, du)) * scale, fv * std::sqrt(dot(dv, dv)) * scale};
          lm[k] = {(p[k].x + X) / (2 * X) * 32, (p[k].z + Z) / (2 * Z) * 32 + p[k].y * 2};
        }
        s.add_quad(m, p, uv, inward, nullptr, lm);
      }
    s.meshes.push_back(m);
  };
  // Subdivisions match along every shared edge (4 along x, 3 along z): a
  // T-junction would leave sub-pixel cracks in any renderer that rounds
  // vertex positions.
  wall(0, 32, {-X, 0, -Z}, {2 * X, 0, 0}, {0, 0, 2 * Z}, {0, 1, 0}, 4, 3);    // floor
  wall(2, 24, {-X, Y, -Z}, {2 * X, 0, 0}, {0, 0, 2 * Z}, {0, -1, 0}, 4, 3);   // ceiling
  wall(1, 48, {-X, 0, Z}, {2 * X, 0, 0}, {0, Y, 0}, {0, 0, -1}, 4, 2);        // far wall (+z)
  wall(1, 48, {-X, 0, -Z}, {2 * X, 0, 0}, {0, Y, 0}, {0, 0, 1}, 4, 2);        // near wall (-z)
  wall(1, 48, {X, 0, -Z}, {0, 0, 2 * Z}, {0, Y, 0}, {-1, 0, 0}, 3, 2);        // right wall (+x)
  wall(1, 48, {-X, 0, -Z}, {0, 0, 2 * Z}, {0, Y, 0}, {1, 0, 0}, 3, 2);        // left wall (-x)

  MeshD crate;
  crate.shading = Shading::texture;
  crate.filter = Filter::nearest;
  add_box(s, {1.6, 0.5, 1.2}, {0.5, 0.5, 0.5}, rot_y(0.3), crate, 32, {}, {3});
  MeshD pillar;
  pillar.shading = Shading::gouraud;
  add_box(s, {-1.8, 1.5, 1.6}, {0.3, 1.5, 0.3}, rot_y(0.7), pillar, 1, {}, {});
  MeshD block;
  block.shading = Shading::flat;
  add_box(s, {2.6, 0.3, -1.6}, {0.6, 0.3, 0.4}, rot_y(-0.4), block, 1, {0x7080A0, 0x506080, 0x607090}, {});

  s.camera = CameraD::look_at({-3.3, 1.55, -2.35}, {2.0, 1.0, 1.5}, {0, 1, 0}, width, height, 72, 0.05, 20);
  return s;
}

Scene make_golden_scene() {
  Scene s;
  s.name = "golden";
  s.width = 240;
  s.height = 180;
  s.clear_color = 0x203040;
  for (int f = 0; f < 3; ++f) {
    Image img(32, 32, 3);
    for (int y = 0; y < 32; ++y)
      for (int x = 0; x < 32; ++x) {
        const int v = ((x ^ y) * (f + 3) + x * y) & 255;
        img.at(x, y, 0) = static_cast<uint8_t>(f == 0 ? v : 255 - v);
        img.at(x, y, 1) = static_cast<uint8_t>((v * 3 + 40 * f) & 255);
        img.at(x, y, 2) = static_cast<uint8_t>(((x + y) * 8) & 255);
      }
    s.textures.push_back(texture("pattern" + std::to_string(f), img));
  }
  // The cube: +-1 around (0, 1, 0), each face its own mesh, bilinear.
  const Vec3d axes[3] = {{1, 0, 0}, {0, 1, 0}, {0, 0, 1}};
  for (int f = 0; f < 6; ++f) {
    const int a = f / 2, b = (a + 1) % 3, c = (a + 2) % 3;
    const double sgn = (f & 1) ? -1.0 : 1.0;
    const double sb[4] = {-1, 1, 1, -1}, sc[4] = {-1, -1, 1, 1};
    Vec3d p[4];
    for (int k = 0; k < 4; ++k) p[k] = Vec3d{0, 1, 0} + axes[a] * sgn + axes[b] * sb[k] + axes[c] * sc[k];
    const Vec2d uv[4] = {{0, 32}, {32, 32}, {32, 0}, {0, 0}};
    MeshD m;
    m.shading = Shading::texture;
    m.texture = f % 3;
    s.add_quad(m, p, uv, axes[a] * sgn);
    s.meshes.push_back(m);
  }
  // A floor reaching behind the camera (near-plane clipping), nearest texels.
  MeshD floor;
  floor.shading = Shading::texture;
  floor.filter = Filter::nearest;
  floor.texture = 2;
  const Vec3d fp[4] = {{-12, 0, -12}, {12, 0, -12}, {12, 0, 12}, {-12, 0, 12}};
  const Vec2d fuv[4] = {{0, 0}, {24 * 16, 0}, {24 * 16, 24 * 16}, {0, 24 * 16}};
  s.add_quad(floor, fp, fuv, {0, 1, 0});
  s.meshes.push_back(floor);
  // A Gouraud triangle and a flat one, both double-sided.
  MeshD g;
  g.shading = Shading::gouraud;
  g.cull = Cull::none;
  for (uint32_t i : {s.add_vertex({2.5, 0, -1}, {}, 0xFF2000), s.add_vertex({3.5, 0, 1}, {}, 0x20FF00),
                     s.add_vertex({3, 2.5, 0}, {}, 0x0040FF)}) {
    g.indices.push_back(i);
  }
  s.meshes.push_back(g);
  MeshD flat;
  flat.shading = Shading::flat;
  flat.cull = Cull::none;
  flat.color = 0xE0C040;
  for (uint32_t i : {s.add_vertex({-3, 0, 1}), s.add_vertex({-2, 0, 2.5}), s.add_vertex({-2.5, 2, 1.5})}) flat.indices.push_back(i);
  s.meshes.push_back(flat);

  // Camera: yaw with cos 0.8 / sin 0.6, pitch with cos 0.96 / sin 0.28, so
  // every rotation entry is a product of exact ratios.
  CameraD c;
  const Vec3d f{0.6 * 0.96, -0.28, 0.8 * 0.96};
  const Vec3d r{-0.8, 0, 0.6};
  const Vec3d d = cross(f, r);
  c.rotation.m[0][0] = r.x, c.rotation.m[0][1] = r.y, c.rotation.m[0][2] = r.z;
  c.rotation.m[1][0] = d.x, c.rotation.m[1][1] = d.y, c.rotation.m[1][2] = d.z;
  c.rotation.m[2][0] = f.x, c.rotation.m[2][1] = f.y, c.rotation.m[2][2] = f.z;
  c.position = Vec3d{0, 1, 0} - f * 6.0;
  c.fx = c.fy = 210;
  c.cx = 120;
  c.cy = 90;
  c.near_z = 0.5;
  c.far_z = 40;
  s.camera = c;
  return s;
}

std::vector<Scene> shared_scenes(int width, int height) {
  std::vector<Scene> v;
  v.push_back(make_cube_scene(width, height));
  v.push_back(make_terrain_scene(width, height));
  v.push_back(make_room_scene(width, height));
  return v;
}

Scene make_view_mapped_scene(const Scene& base, const std::vector<int>& mesh_indices, const Image& view,
                             const CameraD& view_camera) {
  Scene s;
  s.name = base.name + "-from-view";
  s.width = base.width;
  s.height = base.height;
  s.positions = base.positions;
  s.uvs = base.uvs;
  s.colors = base.colors;
  s.lightmap_uvs = base.lightmap_uvs;
  s.camera = base.camera;
  s.clear_color = base.clear_color;
  TextureD t;
  t.name = "view";
  t.image = view;
  t.address = TexAddress::clamp;
  s.textures.push_back(t);
  for (int i : mesh_indices) {
    MeshD m = base.meshes.at(static_cast<size_t>(i));
    m.shading = Shading::view_mapped;
    m.texture = 0;
    m.lightmap = -1;
    m.view_camera = view_camera;
    s.meshes.push_back(m);
  }
  return s;
}

// ---------------------------------------------------------------------------
// Client conversion
// ---------------------------------------------------------------------------
namespace {
Q16_16 q16(double v) { return Q16_16::from_raw(static_cast<int32_t>(std::llround(std::clamp(v, -32767.0, 32767.0) * 65536.0))); }
Q2_30 q30(double v) { return Q2_30::from_raw(static_cast<int32_t>(std::llround(std::clamp(v, -1.999, 1.999) * 1073741824.0))); }
}  // namespace

vds::Camera to_client(const CameraD& c) {
  vds::Camera r{};
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j) r.rotation.m[i][j] = q30(c.rotation.m[i][j]);
  r.position = {q16(c.position.x), q16(c.position.y), q16(c.position.z)};
  r.fx = q16(c.fx);
  r.fy = q16(c.fy);
  r.cx = q16(c.cx);
  r.cy = q16(c.cy);
  r.near_z = q16(c.near_z);
  r.far_z = q16(c.far_z);
  return r;
}

void rgb_to_ycbcr420(const Image& rgb, Image& y, Image& cb, Image& cr) {
  const int w = rgb.width, h = rgb.height, cw = (w + 1) / 2, chh = (h + 1) / 2;
  y = Image(w, h, 1);
  cb = Image(cw, chh, 1);
  cr = Image(cw, chh, 1);
  std::vector<double> fcb(static_cast<size_t>(w) * h), fcr(fcb.size());
  for (int j = 0; j < h; ++j)
    for (int i = 0; i < w; ++i) {
      const double r = rgb.at(i, j, 0), g = rgb.at(i, j, 1), b = rgb.at(i, j, 2);
      y.at(i, j, 0) = clamp8(0.299 * r + 0.587 * g + 0.114 * b);
      fcb[static_cast<size_t>(j) * w + i] = 128 - 0.168736 * r - 0.331264 * g + 0.5 * b;
      fcr[static_cast<size_t>(j) * w + i] = 128 + 0.5 * r - 0.418688 * g - 0.081312 * b;
    }
  for (int j = 0; j < chh; ++j)
    for (int i = 0; i < cw; ++i) {
      double sb = 0, sr = 0;
      for (int dy = 0; dy < 2; ++dy)
        for (int dx = 0; dx < 2; ++dx) {
          const int xx = std::min(2 * i + dx, w - 1), yy = std::min(2 * j + dy, h - 1);
          sb += fcb[static_cast<size_t>(yy) * w + xx];
          sr += fcr[static_cast<size_t>(yy) * w + xx];
        }
      cb.at(i, j, 0) = clamp8(sb / 4);
      cr.at(i, j, 0) = clamp8(sr / 4);
    }
}

Scene client_textures(const Scene& scene, TexFormat format) {
  Scene s = scene;
  for (TextureD& t : s.textures) {
    if (format == TexFormat::rgb565) {
      for (int y = 0; y < t.image.height; ++y)
        for (int x = 0; x < t.image.width; ++x) {
          const uint32_t c = expand565(pack565(pixel(t.image, x, y)));
          t.image.at(x, y, 0) = static_cast<uint8_t>(c >> 16);
          t.image.at(x, y, 1) = static_cast<uint8_t>(c >> 8);
          t.image.at(x, y, 2) = static_cast<uint8_t>(c);
        }
    } else if (format == TexFormat::ycbcr420) {
      rgb_to_ycbcr420(t.image, t.y, t.cb, t.cr);
      t.ycbcr = true;
    }
  }
  return s;
}

ClientScene::ClientScene(const Scene& scene, TexFormat format, bool apron) {
  camera_ = to_client(scene.camera);
  clear_color_ = scene.clear_color;
  for (const Vec3d& p : scene.positions) positions_.push_back({q16(p.x), q16(p.y), q16(p.z)});
  for (const Vec2d& uv : scene.uvs) uvs_.push_back({q16(uv.x), q16(uv.y)});
  colors_ = scene.colors;
  textures_.reserve(scene.textures.size());
  for (const TextureD& t : scene.textures) {
    vds::Texture ct;
    ct.format = format;
    ct.address = t.address;
    ct.width = static_cast<uint16_t>(t.image.width);
    ct.height = static_cast<uint16_t>(t.image.height);
    ct.stride = static_cast<uint32_t>(t.image.width);
    const bool with_apron = apron && format != TexFormat::ycbcr420;
    const size_t stride = static_cast<size_t>(t.image.width) + (with_apron ? 1 : 0);
    const size_t rows = static_cast<size_t>(t.image.height) + (with_apron ? 1 : 0);
    if (format == TexFormat::rgb565) {
      std::vector<uint16_t> px(stride * rows);
      for (int y = 0; y < t.image.height; ++y)
        for (int x = 0; x < t.image.width; ++x) px[static_cast<size_t>(y) * stride + x] = pack565(pixel(t.image, x, y));
      texels16_.push_back(std::move(px));
      ct.texels = texels16_.back().data();
    } else if (format == TexFormat::xrgb8888) {
      std::vector<uint32_t> px(stride * rows);
      for (int y = 0; y < t.image.height; ++y)
        for (int x = 0; x < t.image.width; ++x) px[static_cast<size_t>(y) * stride + x] = pixel(t.image, x, y);
      texels32_.push_back(std::move(px));
      ct.texels = texels32_.back().data();
    } else {
      Image y, cb, cr;
      if (t.ycbcr) {
        y = t.y, cb = t.cb, cr = t.cr;
      } else {
        rgb_to_ycbcr420(t.image, y, cb, cr);
      }
      planes_.push_back(y.pixels);
      ct.texels = planes_.back().data();
      planes_.push_back(cb.pixels);
      ct.cb = planes_.back().data();
      planes_.push_back(cr.pixels);
      ct.cr = planes_.back().data();
      ct.chroma_stride = static_cast<uint32_t>(cb.width);
    }
    textures_.push_back(ct);
  }
  // Point every texture at its storage once all buffers are in place.
  {
    size_t i16 = 0, i32 = 0, ip = 0;
    for (vds::Texture& ct : textures_) {
      void* mut = nullptr;
      if (ct.format == TexFormat::rgb565) {
        mut = texels16_[i16++].data();
      } else if (ct.format == TexFormat::xrgb8888) {
        mut = texels32_[i32++].data();
      } else {
        ct.texels = planes_[ip++].data();
        ct.cb = planes_[ip++].data();
        ct.cr = planes_[ip++].data();
        continue;
      }
      ct.texels = mut;
      if (apron) {
        ct.stride = ct.width + 1u;
        if (vds::texture_fill_apron(ct, mut) != Status::ok) throw std::logic_error("ClientScene: apron");
      }
    }
  }
  indices_.reserve(scene.meshes.size());
  for (const MeshD& m : scene.meshes) {
    std::vector<uint16_t> idx;
    for (uint32_t i : m.indices) {
      if (i > 0xFFFF) throw std::invalid_argument("ClientScene: vertex index above 65535");
      idx.push_back(static_cast<uint16_t>(i));
    }
    indices_.push_back(std::move(idx));
    vds::Mesh cm;
    cm.indices = indices_.back().data();
    cm.num_triangles = static_cast<uint32_t>(m.indices.size() / 3);
    cm.shading = m.shading;
    cm.filter = m.filter;
    cm.cull = m.cull;
    cm.color = m.color;
    cm.colors = colors_.data();
    cm.uvs = uvs_.data();
    cm.texture = m.texture >= 0 ? &textures_.at(static_cast<size_t>(m.texture)) : nullptr;
    if (m.shading == Shading::view_mapped && m.indices.size() >= 3) {
      const vds::Vec3<Q16_16> plane[3] = {positions_[m.indices[0]], positions_[m.indices[1]], positions_[m.indices[2]]};
      if (vds::plane_homography(camera_, to_client(m.view_camera), plane, &cm.view_map) != Status::ok) {
        throw std::invalid_argument("ClientScene: no homography for a view-mapped mesh");
      }
    }
    meshes_.push_back(cm);
  }
  for (size_t i = 0; i < meshes_.size(); ++i) meshes_[i].indices = indices_[i].data();
  list_.positions = positions_.data();
  list_.num_positions = static_cast<uint32_t>(positions_.size());
  list_.meshes = meshes_.data();
  list_.num_meshes = static_cast<uint32_t>(meshes_.size());
}

ClientFrame render_client(const ClientScene& scene, int width, int height, const ClientRenderSettings& settings) {
  return render_client(scene, scene.camera(), width, height, settings);
}

ClientFrame render_client(const ClientScene& scene, const vds::Camera& camera, int width, int height,
                          const ClientRenderSettings& settings) {
  ClientFrame out;
  vds::RenderConfig cfg;
  cfg.width = static_cast<uint16_t>(width);
  cfg.height = static_cast<uint16_t>(height);
  cfg.band_height = static_cast<uint16_t>(std::clamp(settings.band_height, 1, height));
  cfg.format = settings.format;
  cfg.depth = settings.depth;
  cfg.vertex_cache = settings.vertex_cache;
  cfg.triangle_cache = settings.triangle_cache;
  cfg.setup_cache = settings.setup_cache;
  std::vector<uint8_t> workspace(vds::render_workspace_size(cfg));
  vds::Arena arena(workspace.data(), workspace.size());
  vds::Renderer r;
  out.status = r.init(cfg, arena);
  if (out.status != Status::ok) return out;
  const size_t bpp = static_cast<size_t>(bytes_per_pixel(cfg.format));
  out.bytes.assign(static_cast<size_t>(width) * height * bpp, 0);
  struct Ctx {
    std::vector<uint8_t>* bytes;
    size_t row_bytes;
  } ctx{&out.bytes, static_cast<size_t>(width) * bpp};
  out.status = r.render(camera, scene.list(), scene.clear_color(),
                        [](void* p, const vds::Band& b) {
                          auto* c = static_cast<Ctx*>(p);
                          for (int y = 0; y < b.height; ++y) {
                            std::copy_n(b.pixels + static_cast<size_t>(y) * b.stride, c->row_bytes,
                                        c->bytes->data() + (static_cast<size_t>(b.y) + y) * c->row_bytes);
                          }
                          return true;
                        },
                        &ctx);
  out.stats = r.stats();
  out.workspace = arena.used();
  out.image = Image(width, height, 3);
  for (size_t i = 0; i < static_cast<size_t>(width) * height; ++i) {
    uint32_t c;
    if (cfg.format == vds::PixelFormat::rgb565) {
      uint16_t v;
      std::memcpy(&v, out.bytes.data() + 2 * i, 2);
      c = expand565(v);
    } else {
      c = (uint32_t{out.bytes[3 * i]} << 16) | (uint32_t{out.bytes[3 * i + 1]} << 8) | out.bytes[3 * i + 2];
    }
    out.image.pixels[3 * i] = static_cast<uint8_t>(c >> 16);
    out.image.pixels[3 * i + 1] = static_cast<uint8_t>(c >> 8);
    out.image.pixels[3 * i + 2] = static_cast<uint8_t>(c);
  }
  return out;
}

}  // namespace vds::ref
