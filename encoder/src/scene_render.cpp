// vds encoder: the ground-truth renderer of walkthroughs (vds/enc/scene_render.h).
//
// Each frame is drawn in two passes per resolution: a visibility pass that
// rasterises every triangle (near-plane clipped, back faces culled unless
// two-sided, alpha-tested ones cut out) into a buffer of the nearest
// triangle per sample, and a shading pass that samples each visible
// triangle once per sample. Attributes are exact: for a triangle with
// camera-space vertices V0, V1, V2 and normal n, 1/z and each barycentric
// over z are linear in the pixel's ray direction d = ((x - cx) / f,
// (y - cy) / f, 1), so each is a dot product with d, and their screen
// derivatives (for mip-mapping) follow in closed form.
#include "vds/enc/scene_render.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>
#include <unordered_set>
#include <exception>
#include <mutex>
#include <thread>

namespace vds::enc {

namespace {

using V3 = std::array<double, 3>;
V3 sub(const V3& a, const V3& b) { return {a[0] - b[0], a[1] - b[1], a[2] - b[2]}; }
double dot(const V3& a, const V3& b) { return a[0] * b[0] + a[1] * b[1] + a[2] * b[2]; }
V3 cross(const V3& a, const V3& b) {
  return {a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]};
}
V3 scale(const V3& a, double s) { return {a[0] * s, a[1] * s, a[2] * s}; }

// A texture as mip levels of RGBA8, each level's sides half the one above (rounded down, at least 1).
struct Level {
  int w = 0, h = 0;
  std::vector<uint8_t> px;  // RGBA
};
struct Texture {
  std::vector<Level> levels;
  std::array<float, 3> mean{};  // of level 0 (the sky's colour)
};

Level half(const Level& a) {
  Level r;
  r.w = std::max(1, a.w / 2);
  r.h = std::max(1, a.h / 2);
  r.px.resize(static_cast<size_t>(r.w) * r.h * 4);
  for (int y = 0; y < r.h; ++y)
    for (int x = 0; x < r.w; ++x) {
      const int x0 = std::min(2 * x, a.w - 1), x1 = std::min(2 * x + 1, a.w - 1);
      const int y0 = std::min(2 * y, a.h - 1), y1 = std::min(2 * y + 1, a.h - 1);
      for (int c = 0; c < 4; ++c) {
        const int s = a.px[(static_cast<size_t>(y0) * a.w + x0) * 4 + c] + a.px[(static_cast<size_t>(y0) * a.w + x1) * 4 + c] +
                      a.px[(static_cast<size_t>(y1) * a.w + x0) * 4 + c] + a.px[(static_cast<size_t>(y1) * a.w + x1) * 4 + c];
        r.px[(static_cast<size_t>(y) * r.w + x) * 4 + c] = static_cast<uint8_t>((s + 2) / 4);
      }
    }
  return r;
}

inline int wrap(int i, int n) {
  const int m = i % n;
  return m < 0 ? m + n : m;
}

struct Rgba {
  float c[4];
};

// Bilinear at level `l`, (u, v) in units of the texture (1 = one repeat).
inline Rgba bilinear(const Level& l, double u, double v) {
  const double x = u * l.w - 0.5, y = v * l.h - 0.5;
  const double fx = std::floor(x), fy = std::floor(y);
  const float a = static_cast<float>(x - fx), b = static_cast<float>(y - fy);
  // Wrap far-off coordinates into range first (texture coordinates can be large).
  const int ix = wrap(static_cast<int>(std::fmod(fx, static_cast<double>(l.w) * 1024)), l.w);
  const int iy = wrap(static_cast<int>(std::fmod(fy, static_cast<double>(l.h) * 1024)), l.h);
  const int ix1 = ix + 1 == l.w ? 0 : ix + 1, iy1 = iy + 1 == l.h ? 0 : iy + 1;
  const uint8_t* p00 = &l.px[(static_cast<size_t>(iy) * l.w + ix) * 4];
  const uint8_t* p10 = &l.px[(static_cast<size_t>(iy) * l.w + ix1) * 4];
  const uint8_t* p01 = &l.px[(static_cast<size_t>(iy1) * l.w + ix) * 4];
  const uint8_t* p11 = &l.px[(static_cast<size_t>(iy1) * l.w + ix1) * 4];
  Rgba r;
  for (int c = 0; c < 4; ++c) {
    const float top = p00[c] + (p10[c] - p00[c]) * a;
    const float bot = p01[c] + (p11[c] - p01[c]) * a;
    r.c[c] = top + (bot - top) * b;
  }
  return r;
}

inline Rgba trilinear(const Texture& t, double u, double v, double lod) {
  const int top = static_cast<int>(t.levels.size()) - 1;
  if (lod <= 0) return bilinear(t.levels[0], u, v);
  if (lod >= top) return bilinear(t.levels[static_cast<size_t>(top)], u, v);
  const int k = static_cast<int>(lod);
  const float a = static_cast<float>(lod - k);
  const Rgba c0 = bilinear(t.levels[static_cast<size_t>(k)], u, v), c1 = bilinear(t.levels[static_cast<size_t>(k) + 1], u, v);
  Rgba r;
  for (int c = 0; c < 4; ++c) r.c[c] = c0.c[c] + (c1.c[c] - c0.c[c]) * a;
  return r;
}

// Colour-preserving overbright: x 2^bits, then scaled down so the largest channel is at most 255.
std::array<float, 3> overbright(const uint8_t* rgb, int bits) {
  double c[3] = {rgb[0] * std::ldexp(1.0, bits), rgb[1] * std::ldexp(1.0, bits), rgb[2] * std::ldexp(1.0, bits)};
  const double m = std::max({c[0], c[1], c[2]});
  const double s = m > 255 ? 255 / m : 1;
  return {static_cast<float>(c[0] * s), static_cast<float>(c[1] * s), static_cast<float>(c[2] * s)};
}

enum Light : uint8_t { kLightIdentity, kLightLightmap, kLightVertex };

struct Tri {
  uint32_t v[3];
  int32_t texture;  // -1 none
  int32_t lightmap;
  SurfaceKind kind;
  Light light;
  bool two_sided, alpha_test;
  V3 normal;  // world, towards the front side
};

}  // namespace

struct SceneRenderer::Prepared {
  std::vector<Tri> tris;
  std::vector<V3> pos;
  std::vector<std::array<double, 2>> uv, lm_uv;
  std::vector<std::array<float, 3>> vcolor;  // overbright vertex colours
  std::vector<Texture> textures;
  std::vector<std::vector<float>> lightmaps;  // kLightmapSide^2 RGB, overbright
};

SceneCamera scene_camera(const CameraPose& pose, double hfov_deg, int width, int height) {
  SceneCamera c;
  const double kDeg = 3.14159265358979323846 / 180;
  const double y = pose.yaw_deg * kDeg, p = pose.pitch_deg * kDeg;
  c.position = {pose.x, pose.y, pose.z};
  c.forward = {std::cos(p) * std::cos(y), std::cos(p) * std::sin(y), std::sin(p)};
  c.right = {std::sin(y), -std::cos(y), 0};
  c.down = cross(c.forward, c.right);  // forward x right points down for Z up
  c.width = width;
  c.height = height;
  c.focal = (width / 2.0) / std::tan(hfov_deg * kDeg / 2);
  c.cx = width / 2.0;
  c.cy = height / 2.0;
  return c;
}

SceneRenderer::SceneRenderer(const Scene& scene, std::vector<io::Image> images, const RenderOptions& o)
    : opt_(o), p_(new Prepared) {
  if (o.width < 1 || o.height < 1 || o.width > 8192 || o.height > 8192 || o.supersample < 1 || o.supersample > 8 ||
      o.max_aniso < 1 || o.max_aniso > 16 || o.overbright_bits < 0 || o.overbright_bits > 4 || !(o.near_m > 0) ||
      !(scene.metres_per_unit > 0)) {
    delete p_;
    throw std::invalid_argument("render options out of range");
  }
  Prepared& P = *p_;
  const int bits = scene.overbright ? o.overbright_bits : 0;
  opt_.near_z = o.near_m / scene.metres_per_unit;
  for (const SceneVertex& v : scene.vertices) {
    P.pos.push_back({v.pos[0], v.pos[1], v.pos[2]});
    P.uv.push_back({v.uv[0], v.uv[1]});
    P.lm_uv.push_back({v.lm_uv[0], v.lm_uv[1]});
    P.vcolor.push_back(overbright(v.color.data(), bits));
  }
  P.textures.resize(scene.textures.size());
  for (size_t t = 0; t < scene.textures.size(); ++t) {
    Level l0;
    const io::Image* img = t < images.size() && images[t].width > 0 ? &images[t] : nullptr;
    if (img != nullptr && img->channels == 4) {
      l0.w = img->width, l0.h = img->height, l0.px = img->pixels;
    } else {
      l0.w = l0.h = 1, l0.px = {128, 128, 128, 255};
    }
    double sum[3] = {0, 0, 0};
    for (size_t i = 0; i < l0.px.size(); i += 4)
      for (int c = 0; c < 3; ++c) sum[c] += l0.px[i + static_cast<size_t>(c)];
    const double n = static_cast<double>(l0.px.size() / 4);
    for (int c = 0; c < 3; ++c) P.textures[t].mean[static_cast<size_t>(c)] = static_cast<float>(sum[c] / n);
    P.textures[t].levels.push_back(std::move(l0));
    while (P.textures[t].levels.back().w > 1 || P.textures[t].levels.back().h > 1)
      P.textures[t].levels.push_back(half(P.textures[t].levels.back()));
  }
  // Last: mid grey, for triangles with no texture.
  const int32_t grey = static_cast<int32_t>(P.textures.size());
  P.textures.emplace_back();
  P.textures.back().levels.push_back(Level{1, 1, {128, 128, 128, 255}});
  P.textures.back().mean = {128, 128, 128};
  for (const auto& lm : scene.lightmaps) {
    std::vector<float> f(lm.size());
    for (size_t i = 0; i + 2 < lm.size(); i += 3) {
      const auto c = overbright(&lm[i], bits);
      f[i] = c[0], f[i + 1] = c[1], f[i + 2] = c[2];
    }
    P.lightmaps.push_back(std::move(f));
  }
  P.tris.resize(scene.triangles());
  for (const SceneSurface& s : scene.surfaces) {
    const SceneTexture* tex =
        s.texture >= 0 && static_cast<size_t>(s.texture) < scene.textures.size() ? &scene.textures[static_cast<size_t>(s.texture)] : nullptr;
    for (uint32_t i = s.first_index; i < s.first_index + s.index_count; i += 3) {
      Tri& t = P.tris[i / 3];
      for (int k = 0; k < 3; ++k) t.v[k] = scene.indices[i + static_cast<uint32_t>(k)];
      t.texture = s.texture >= 0 && static_cast<size_t>(s.texture) < scene.textures.size() ? s.texture : grey;
      t.lightmap = s.lightmap;
      t.kind = s.kind;
      t.light = s.lightmap >= 0 && static_cast<size_t>(s.lightmap) < P.lightmaps.size() ? kLightLightmap
                : tex != nullptr && tex->vertex_colour                                    ? kLightVertex
                                                                                          : kLightIdentity;
      t.alpha_test = tex != nullptr && tex->blend == ShaderBlend::alpha_test;
      // The geometric normal, turned to the side the vertex normals face.
      const V3 n = cross(sub(P.pos[t.v[1]], P.pos[t.v[0]]), sub(P.pos[t.v[2]], P.pos[t.v[0]]));
      V3 vn{0, 0, 0};
      for (int k = 0; k < 3; ++k)
        for (int c = 0; c < 3; ++c) vn[static_cast<size_t>(c)] += scene.vertices[t.v[k]].normal[static_cast<size_t>(c)];
      const double d = dot(n, vn);
      t.two_sided = (tex != nullptr && tex->two_sided) || d == 0 || s.kind == SurfaceKind::additive;
      t.normal = d < 0 ? scale(n, -1) : n;
    }
  }
}

SceneRenderer::~SceneRenderer() { delete p_; }

namespace {

// A triangle set up for one camera: camera-space vertices and the linear
// forms of 1/z and barycentrics / z in the ray direction.
struct Setup {
  V3 q, b1, b2;  // 1/z = q.d, b1/z = b1.d, b2/z = b2.d
};

// Camera-space position of a world point.
inline V3 to_cam(const SceneCamera& c, const V3& p) {
  const V3 d = sub(p, c.position);
  return {dot(d, c.right), dot(d, c.down), dot(d, c.forward)};
}

bool setup(const V3 v[3], Setup* s) {
  const V3 e1 = sub(v[1], v[0]), e2 = sub(v[2], v[0]);
  const V3 n = cross(e1, e2);
  const double nn = dot(n, n), nv = dot(n, v[0]);
  if (nn == 0 || std::fabs(nv) < 1e-9 * std::sqrt(nn)) return false;  // degenerate, or its plane passes through the eye
  const V3 g1 = scale(cross(e2, n), 1 / nn), g2 = scale(cross(n, e1), 1 / nn);
  s->q = scale(n, 1 / nv);
  s->b1 = sub(g1, scale(s->q, dot(g1, v[0])));
  s->b2 = sub(g2, scale(s->q, dot(g2, v[0])));
  return true;
}

// A target of the visibility pass: nearest 1/z and triangle per sample.
struct Target {
  int w, h;
  double f, cx, cy;
  std::vector<float> iz;
  std::vector<uint32_t> tri;
};

struct Interp {
  double w0, w1, w2;                 // barycentrics
  double dw1x, dw1y, dw2x, dw2y;     // their derivatives per sample
  double iz;
};

inline Interp interpolate(const Setup& s, const Target& t, double x, double y) {
  const double dx = (x - t.cx) / t.f, dy = (y - t.cy) / t.f;
  const double iz = s.q[0] * dx + s.q[1] * dy + s.q[2];
  const double a1 = s.b1[0] * dx + s.b1[1] * dy + s.b1[2], a2 = s.b2[0] * dx + s.b2[1] * dy + s.b2[2];
  Interp r;
  r.iz = iz;
  r.w1 = a1 / iz;
  r.w2 = a2 / iz;
  r.w0 = 1 - r.w1 - r.w2;
  const double qx = s.q[0] / t.f, qy = s.q[1] / t.f, iz2 = iz * iz;
  r.dw1x = (s.b1[0] / t.f * iz - a1 * qx) / iz2;
  r.dw1y = (s.b1[1] / t.f * iz - a1 * qy) / iz2;
  r.dw2x = (s.b2[0] / t.f * iz - a2 * qx) / iz2;
  r.dw2y = (s.b2[1] / t.f * iz - a2 * qy) / iz2;
  return r;
}

struct Sampled {
  float rgb[3];
  float alpha;
};

class Frame {
 public:
  Frame(const SceneRenderer::Prepared& p, const RenderOptions& o, const SceneCamera& cam) : P(p), O(o), cam_(cam) {
    cv_.resize(P.pos.size());
    for (size_t i = 0; i < P.pos.size(); ++i) cv_[i] = to_cam(cam, P.pos[i]);
    setups_.resize(P.tris.size());
    ok_.assign(P.tris.size(), 0);
    for (size_t i = 0; i < P.tris.size(); ++i) {
      const Tri& t = P.tris[i];
      if (t.kind == SurfaceKind::fog) continue;
      // Back faces: the front side's normal points away from the eye.
      if (!t.two_sided && dot(t.normal, sub(P.pos[t.v[0]], cam.position)) >= 0) continue;
      const V3 v[3] = {cv_[t.v[0]], cv_[t.v[1]], cv_[t.v[2]]};
      if (v[0][2] <= o.near_z && v[1][2] <= o.near_z && v[2][2] <= o.near_z) continue;
      ok_[i] = setup(v, &setups_[i]) ? 1 : 0;
    }
  }

  // Rasterises every drawn triangle of `pass` (opaque and sky, or additive) into `t`.
  template <class Visit>
  void raster_all(Target& t, bool additive, Visit&& visit) const {
    for (size_t i = 0; i < P.tris.size(); ++i) {
      if (!ok_[i] || (P.tris[i].kind == SurfaceKind::additive) != additive) continue;
      raster(t, static_cast<uint32_t>(i), visit);
    }
  }

  // The nearest triangle at each sample, of those `skip` (if given) does not mark.
  void visibility(Target& t, const std::vector<bool>* skip = nullptr) const {
    t.iz.assign(static_cast<size_t>(t.w) * t.h, 0.0f);
    t.tri.assign(static_cast<size_t>(t.w) * t.h, kNoTriangle);
    raster_all(t, false, [&](uint32_t tri, size_t idx, double x, double y) {
      if (skip != nullptr && (*skip)[tri]) return;
      const Interp in = interpolate(setups_[tri], t, x, y);
      if (!(in.iz > t.iz[idx])) return;
      if (P.tris[tri].alpha_test && shade(tri, in, true).alpha < 127.5f) return;
      t.iz[idx] = static_cast<float>(in.iz);
      t.tri[idx] = tri;
    });
  }

  // The colour of triangle `tri` at a sample; `alpha_only` skips lighting.
  Sampled shade(uint32_t tri, const Interp& in, bool alpha_only = false) const {
    const Tri& t = P.tris[tri];
    Sampled s{};
    s.alpha = 255;
    if (t.kind == SurfaceKind::sky) {
      const auto& m = P.textures[static_cast<size_t>(t.texture)].mean;
      s.rgb[0] = m[0], s.rgb[1] = m[1], s.rgb[2] = m[2];
      return s;
    }
    const auto& uv0 = P.uv[t.v[0]];
    const auto& uv1 = P.uv[t.v[1]];
    const auto& uv2 = P.uv[t.v[2]];
    const double u = in.w0 * uv0[0] + in.w1 * uv1[0] + in.w2 * uv2[0];
    const double v = in.w0 * uv0[1] + in.w1 * uv1[1] + in.w2 * uv2[1];
    // d(uv)/dx = uv0 dw0 + uv1 dw1 + uv2 dw2 with dw0 = -dw1 - dw2.
    const double dudx = (uv1[0] - uv0[0]) * in.dw1x + (uv2[0] - uv0[0]) * in.dw2x;
    const double dudy = (uv1[0] - uv0[0]) * in.dw1y + (uv2[0] - uv0[0]) * in.dw2y;
    const double dvdx = (uv1[1] - uv0[1]) * in.dw1x + (uv2[1] - uv0[1]) * in.dw2x;
    const double dvdy = (uv1[1] - uv0[1]) * in.dw1y + (uv2[1] - uv0[1]) * in.dw2y;
    const Texture& tex = P.textures[static_cast<size_t>(t.texture)];
    const double tw = tex.levels[0].w, th = tex.levels[0].h;
    const double ax = dudx * tw, ay = dvdx * th, bx = dudy * tw, by = dvdy * th;
    const double la = std::sqrt(ax * ax + ay * ay), lb = std::sqrt(bx * bx + by * by);
    const double major = std::max(la, lb), minor = std::min(la, lb);
    int n = 1;
    if (!alpha_only && minor > 0 && O.max_aniso > 1) n = std::min(O.max_aniso, static_cast<int>(std::ceil(major / minor - 1e-9)));
    if (minor == 0 && major > 0 && !alpha_only) n = O.max_aniso;
    const double lod = major > 0 ? std::log2(major / n) : 0;
    float acc[4] = {0, 0, 0, 0};
    const double su = la >= lb ? dudx : dudy, sv = la >= lb ? dvdx : dvdy;
    for (int k = 0; k < n; ++k) {
      const double o = n == 1 ? 0 : (k + 0.5) / n - 0.5;
      const Rgba c = trilinear(tex, u + o * su, v + o * sv, lod);
      for (int ch = 0; ch < 4; ++ch) acc[ch] += c.c[ch];
    }
    const float inv = 1.0f / static_cast<float>(n);
    s.alpha = acc[3] * inv;
    if (alpha_only) return s;
    float light[3] = {255, 255, 255};
    if (t.light == kLightLightmap) {
      const auto& l0 = P.lm_uv[t.v[0]];
      const auto& l1 = P.lm_uv[t.v[1]];
      const auto& l2 = P.lm_uv[t.v[2]];
      const double lu = in.w0 * l0[0] + in.w1 * l1[0] + in.w2 * l2[0];
      const double lv = in.w0 * l0[1] + in.w1 * l1[1] + in.w2 * l2[1];
      lightmap(P.lightmaps[static_cast<size_t>(t.lightmap)], lu, lv, light);
    } else if (t.light == kLightVertex) {
      for (int c = 0; c < 3; ++c)
        light[c] = static_cast<float>(in.w0 * P.vcolor[t.v[0]][static_cast<size_t>(c)] + in.w1 * P.vcolor[t.v[1]][static_cast<size_t>(c)] +
                                      in.w2 * P.vcolor[t.v[2]][static_cast<size_t>(c)]);
    }
    for (int c = 0; c < 3; ++c) s.rgb[c] = acc[c] * inv * light[c] / 255.0f;
    return s;
  }

  const std::vector<Setup>& setups() const { return setups_; }

 private:
  // Bilinear, clamped to the lightmap's edge.
  static void lightmap(const std::vector<float>& lm, double u, double v, float out[3]) {
    const double x = std::clamp(u * kLightmapSide - 0.5, 0.0, kLightmapSide - 1.0);
    const double y = std::clamp(v * kLightmapSide - 0.5, 0.0, kLightmapSide - 1.0);
    const int x0 = static_cast<int>(x), y0 = static_cast<int>(y);
    const int x1 = std::min(x0 + 1, kLightmapSide - 1), y1 = std::min(y0 + 1, kLightmapSide - 1);
    const float a = static_cast<float>(x - x0), b = static_cast<float>(y - y0);
    for (int c = 0; c < 3; ++c) {
      const auto at = [&](int xx, int yy) { return lm[(static_cast<size_t>(yy) * kLightmapSide + xx) * 3 + static_cast<size_t>(c)]; };
      const float top = at(x0, y0) + (at(x1, y0) - at(x0, y0)) * a, bot = at(x0, y1) + (at(x1, y1) - at(x0, y1)) * a;
      out[c] = top + (bot - top) * b;
    }
  }

  // The triangle clipped to z >= near, projected, as a fan; calls
  // visit(tri, sample index, x, y) for every sample centre inside.
  template <class Visit>
  void raster(Target& t, uint32_t tri, Visit& visit) const {
    const Tri& tr = P.tris[tri];
    V3 in[3] = {cv_[tr.v[0]], cv_[tr.v[1]], cv_[tr.v[2]]};
    V3 poly[4];
    int n = 0;
    const double nz = O.near_z;
    for (int k = 0; k < 3; ++k) {
      const V3& a = in[k];
      const V3& b = in[(k + 1) % 3];
      const bool ain = a[2] >= nz, bin = b[2] >= nz;
      if (ain) poly[n++] = a;
      if (ain != bin) {
        const double s = (nz - a[2]) / (b[2] - a[2]);
        poly[n++] = {a[0] + (b[0] - a[0]) * s, a[1] + (b[1] - a[1]) * s, nz};
      }
    }
    if (n < 3) return;
    double sx[4], sy[4];
    for (int k = 0; k < n; ++k) {
      sx[k] = t.cx + t.f * poly[k][0] / poly[k][2];
      sy[k] = t.cy + t.f * poly[k][1] / poly[k][2];
    }
    for (int k = 1; k + 1 < n; ++k) fill(t, tri, sx[0], sy[0], sx[k], sy[k], sx[k + 1], sy[k + 1], visit);
  }

  template <class Visit>
  static void fill(Target& t, uint32_t tri, double x0, double y0, double x1, double y1, double x2, double y2, Visit& visit) {
    double area = (x1 - x0) * (y2 - y0) - (x2 - x0) * (y1 - y0);
    if (area == 0 || !std::isfinite(area)) return;
    if (area < 0) std::swap(x1, x2), std::swap(y1, y2);
    const int xa = std::max(0, static_cast<int>(std::floor(std::min({x0, x1, x2}) - 0.5)));
    const int xb = std::min(t.w - 1, static_cast<int>(std::ceil(std::max({x0, x1, x2}) - 0.5)));
    const int ya = std::max(0, static_cast<int>(std::floor(std::min({y0, y1, y2}) - 0.5)));
    const int yb = std::min(t.h - 1, static_cast<int>(std::ceil(std::max({y0, y1, y2}) - 0.5)));
    if (xa > xb || ya > yb) return;
    // Edge k: e(x, y) = A x + B y + C, >= 0 inside.
    const double A0 = y1 - y2, B0 = x2 - x1, C0 = x1 * y2 - x2 * y1;
    const double A1 = y2 - y0, B1 = x0 - x2, C1 = x2 * y0 - x0 * y2;
    const double A2 = y0 - y1, B2 = x1 - x0, C2 = x0 * y1 - x1 * y0;
    for (int y = ya; y <= yb; ++y) {
      const double py = y + 0.5;
      const double r0 = B0 * py + C0, r1 = B1 * py + C1, r2 = B2 * py + C2;
      // The span of x inside all three edges.
      double lo = xa + 0.5, hi = xb + 0.5;
      bool empty = false;
      const auto clip = [&](double A, double r) {
        if (A > 0) lo = std::max(lo, -r / A);
        else if (A < 0) hi = std::min(hi, -r / A);
        else if (r < 0) empty = true;
      };
      clip(A0, r0), clip(A1, r1), clip(A2, r2);
      if (empty || lo > hi) continue;
      const int i0 = std::max(xa, static_cast<int>(std::ceil(lo - 0.5)));
      const int i1 = std::min(xb, static_cast<int>(std::floor(hi - 0.5)));
      for (int x = i0; x <= i1; ++x) {
        const double px = x + 0.5;
        if (A0 * px + r0 < 0 || A1 * px + r1 < 0 || A2 * px + r2 < 0) continue;
        visit(tri, static_cast<size_t>(y) * t.w + x, px, py);
      }
    }
  }

  const SceneRenderer::Prepared& P;
  const RenderOptions& O;
  SceneCamera cam_;
  std::vector<V3> cv_;
  std::vector<Setup> setups_;
  std::vector<uint8_t> ok_;
};

}  // namespace

SceneFrame SceneRenderer::render(const CameraPose& pose, double hfov_deg) const {
  const SceneCamera cam = scene_camera(pose, hfov_deg, opt_.width, opt_.height);
  const Frame fr(*p_, opt_, cam);
  const int ss = opt_.supersample;
  // Supersampled colour.
  Target t{opt_.width * ss, opt_.height * ss, cam.focal * ss, cam.cx * ss, cam.cy * ss, {}, {}};
  fr.visibility(t);
  std::vector<float> col(static_cast<size_t>(t.w) * t.h * 3, 0.0f);
  for (int y = 0; y < t.h; ++y)
    for (int x = 0; x < t.w; ++x) {
      const size_t idx = static_cast<size_t>(y) * t.w + x;
      const uint32_t tri = t.tri[idx];
      if (tri == kNoTriangle) continue;
      const Sampled s = fr.shade(tri, interpolate(fr.setups()[tri], t, x + 0.5, y + 0.5));
      for (int c = 0; c < 3; ++c) col[idx * 3 + static_cast<size_t>(c)] = s.rgb[c];
    }
  // Additive effects over what is in front of nothing nearer.
  fr.raster_all(t, true, [&](uint32_t tri, size_t idx, double x, double y) {
    const Interp in = interpolate(fr.setups()[tri], t, x, y);
    if (!(in.iz > t.iz[idx])) return;
    const Sampled s = fr.shade(tri, in);
    for (int c = 0; c < 3; ++c) col[idx * 3 + static_cast<size_t>(c)] += s.rgb[c];
  });
  SceneFrame out;
  out.rgb = io::Image(opt_.width, opt_.height, 3);
  const float norm = 1.0f / static_cast<float>(ss * ss);
  for (int y = 0; y < opt_.height; ++y)
    for (int x = 0; x < opt_.width; ++x)
      for (int c = 0; c < 3; ++c) {
        float sum = 0;
        for (int j = 0; j < ss; ++j)
          for (int i = 0; i < ss; ++i)
            sum += std::min(255.0f, col[((static_cast<size_t>(y) * ss + j) * t.w + static_cast<size_t>(x) * ss + i) * 3 + static_cast<size_t>(c)]);
        out.rgb.at(x, y, c) = static_cast<uint8_t>(std::lround(sum * norm));
      }
  // Visibility at the output's pixel centres.
  Target v{opt_.width, opt_.height, cam.focal, cam.cx, cam.cy, {}, {}};
  fr.visibility(v);
  if (opt_.min_pixels > 1) {
    // Again without the triangles covering fewer than min_pixels pixels.
    std::vector<uint32_t> cover(fr.setups().size(), 0);
    for (uint32_t id : v.tri)
      if (id != kNoTriangle) ++cover[id];
    std::vector<bool> small(cover.size());
    for (size_t i = 0; i < cover.size(); ++i) small[i] = cover[i] > 0 && cover[i] < opt_.min_pixels;
    Target large{opt_.width, opt_.height, cam.focal, cam.cx, cam.cy, {}, {}};
    fr.visibility(large, &small);
    out.large_ids = std::move(large.tri);
  }
  out.ids = std::move(v.tri);
  out.depth.resize(v.iz.size());
  for (size_t i = 0; i < v.iz.size(); ++i)
    out.depth[i] = v.iz[i] > 0 ? 1.0f / v.iz[i] : std::numeric_limits<float>::infinity();
  return out;
}

namespace {
std::vector<std::pair<uint32_t, uint32_t>> count_ids(std::vector<uint32_t> ids) {
  std::sort(ids.begin(), ids.end());
  std::vector<std::pair<uint32_t, uint32_t>> out;
  for (size_t i = 0; i < ids.size();) {
    size_t j = i;
    while (j < ids.size() && ids[j] == ids[i]) ++j;
    out.emplace_back(ids[i], static_cast<uint32_t>(j - i));
    i = j;
  }
  return out;
}
}  // namespace

std::vector<std::pair<uint32_t, uint32_t>> triangle_pixels(const std::vector<uint32_t>& ids) {
  std::vector<uint32_t> shown;
  shown.reserve(ids.size());
  for (uint32_t id : ids)
    if (id != kNoTriangle) shown.push_back(id);
  return count_ids(std::move(shown));
}

std::vector<std::pair<uint32_t, uint32_t>> visible_triangles(const SceneFrame& f) { return triangle_pixels(f.ids); }

std::vector<uint32_t> drawn_triangle_ids(const SceneFrame& f) {
  if (f.large_ids.empty()) return f.ids;
  if (f.large_ids.size() != f.ids.size()) throw std::invalid_argument("drawn_triangle_ids: large_ids of another size");
  // A small triangle is one whose pixels large_ids does not show it at. It
  // stays where what lies behind it is nothing, or a triangle the frame
  // does not show elsewhere (the view through a grille of small ones).
  std::unordered_set<uint32_t> shown;
  for (size_t i = 0; i < f.ids.size(); ++i)
    if (f.ids[i] != kNoTriangle && f.ids[i] == f.large_ids[i]) shown.insert(f.ids[i]);
  std::unordered_set<uint32_t> stays;
  for (size_t i = 0; i < f.ids.size(); ++i)
    if (f.ids[i] != kNoTriangle && f.large_ids[i] != f.ids[i] && shown.count(f.large_ids[i]) == 0) stays.insert(f.ids[i]);
  std::vector<uint32_t> out(f.ids.size());
  for (size_t i = 0; i < f.ids.size(); ++i) {
    const uint32_t id = f.ids[i];
    out[i] = id == kNoTriangle || f.large_ids[i] == id || stays.count(id) != 0 ? id : f.large_ids[i];
  }
  return out;
}

std::vector<std::pair<uint32_t, uint32_t>> visible_large_triangles(const SceneFrame& f) {
  return triangle_pixels(drawn_triangle_ids(f));
}

void render_path(const SceneRenderer& r, const CameraPath& path, int threads,
                 const std::function<void(size_t, const SceneFrame&)>& sink, const std::function<void(size_t)>& progress) {
  const size_t n = path.frames.size();
  const size_t workers = threads > 0 ? static_cast<size_t>(threads) : std::max(1u, std::thread::hardware_concurrency());
  // Batches of a few frames per worker: drawn in parallel, handed on in order.
  const size_t batch = workers * 4;
  std::vector<SceneFrame> frames(batch);
  for (size_t start = 0; start < n; start += batch) {
    const size_t count = std::min(batch, n - start);
    std::vector<std::thread> pool;
    std::exception_ptr error;
    std::mutex error_mutex;
    for (size_t w = 0; w < std::min(workers, count); ++w)
      pool.emplace_back([&, w] {
        try {
          for (size_t i = w; i < count; i += workers) frames[i] = r.render(path.frames[start + i], path.hfov_deg);
        } catch (...) {
          const std::lock_guard<std::mutex> lock(error_mutex);
          error = std::current_exception();
        }
      });
    for (std::thread& t : pool) t.join();
    if (error) std::rethrow_exception(error);
    for (size_t i = 0; i < count; ++i) sink(start + i, frames[i]);
    if (progress) progress(start + count);
  }
}

}  // namespace vds::enc
