// Benchmark driver for the vds image codec against libjpeg-turbo
// (bench/run_texture.sh runs it and writes bench/results/texture.md).
//
//   bench_texture views TEXDIR OUTDIR       render the view set (PNG) from textures
//   bench_texture rd LIST CSV [--quick]     rate-distortion points of vds and of
//                                           cjpeg -optimize / -arithmetic (djpeg
//                                           decodes), one CSV line per point
//   bench_texture bd CSV MD PLOTCSV         BD-rates (Bjontegaard, PCHIP over
//                                           0.25..2 bpp) as markdown
//   bench_texture decode FILE N             plays FILE (a .vds image stream, or a .jpg
//                                           wrapped in JPEG chunks) N times through
//                                           vds::Player to an RGB565 frame (for callgrind)
//   bench_texture make-vds IN OUT.vds PSNR [SLOPE]
//                                           encodes IN at the smallest size reaching
//                                           PSNR (RGB dB); prints bytes and PSNR
//   bench_texture m4-case FILE OUT REPS     wraps a .vds stream or .jpg as a case file
//                                           for the board firmware vds_fw_bench_texture
//                                           (firmware_sim/app/bench_texture.cpp), a .jpg
//                                           wrapped in JPEG chunks; prints the host's
//                                           CRC-32C of the played RGB565 frame
//   bench_texture psnr A B                  RGB PSNR of two image files
//   bench_texture workspace                 the decoders' workspace and object sizes
//
// LIST lines: "NAME PATH" (PATH: PNG/TGA/JPEG). The tools cjpeg/djpeg come from
// PATH (libjpeg-turbo-progs).
#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <map>
#include <numeric>
#include <sstream>
#include <stdexcept>
#include <string>
#include <vector>

#include <unistd.h>

#include "vds/enc/image_codec.h"
#include "vds/enc/image_io.h"
#include "vds/crc32c.h"
#include "vds/enc/stream_writer.h"
#include "vds/image.h"
#include "vds/jpeg.h"
#include "vds/player.h"

namespace {

using vds::enc::Image;

// --- small helpers -------------------------------------------------------------

std::string tmpdir() {
  static std::string d = [] {
    char tmpl[] = "/tmp/bench_texture_XXXXXX";
    const char* p = mkdtemp(tmpl);
    if (p == nullptr) throw std::runtime_error("mkdtemp failed");
    return std::string(p);
  }();
  return d;
}

void run(const std::string& cmd) {
  if (std::system(cmd.c_str()) != 0) throw std::runtime_error("command failed: " + cmd);
}

void write_ppm(const std::string& path, const Image& img) {
  std::ofstream f(path, std::ios::binary);
  f << "P6\n" << img.width << " " << img.height << "\n255\n";
  for (int y = 0; y < img.height; ++y)
    for (int x = 0; x < img.width; ++x)
      for (int c = 0; c < 3; ++c) f.put(static_cast<char>(img.channels >= 3 ? img.at(x, y, c) : img.at(x, y, 0)));
}

Image rgb_of(const Image& img) {
  Image out(img.width, img.height, 3);
  for (int y = 0; y < img.height; ++y)
    for (int x = 0; x < img.width; ++x)
      for (int c = 0; c < 3; ++c) out.at(x, y, c) = img.channels >= 3 ? img.at(x, y, c) : img.at(x, y, 0);
  return out;
}

double psnr_rgb(const Image& a, const Image& b) { return vds::enc::psnr(a, b); }

// PSNR of Y' (JFIF luma of the RGB images), the usual second measure.
double psnr_luma(const Image& a, const Image& b) {
  double sse = 0;
  for (int y = 0; y < a.height; ++y)
    for (int x = 0; x < a.width; ++x) {
      const auto lum = [&](const Image& i) {
        return 0.299 * i.at(x, y, 0) + 0.587 * i.at(x, y, 1) + 0.114 * i.at(x, y, 2);
      };
      const double d = lum(a) - lum(b);
      sse += d * d;
    }
  return 10.0 * std::log10(255.0 * 255.0 * a.width * a.height / std::max(sse, 1e-9));
}

struct Item {
  std::string name, path;
};

std::vector<Item> read_list(const std::string& path) {
  std::ifstream f(path);
  if (!f) throw std::runtime_error("cannot open " + path);
  std::vector<Item> items;
  std::string line;
  while (std::getline(f, line)) {
    if (line.empty() || line[0] == '#') continue;
    std::istringstream s(line);
    Item it;
    s >> it.name >> it.path;
    if (!it.path.empty()) items.push_back(it);
  }
  return items;
}

// --- rendered views ----------------------------------------------------------------
// A room (floor, ceiling, four walls) ray-cast with perspective, bilinear
// texture filtering, 2x2 supersampling, and a soft light falloff: the kind of
// frame a walkthrough streams.

struct Tex {
  Image img;
  double sample(double u, double v, int c) const {
    u = u - std::floor(u);
    v = v - std::floor(v);
    const double x = u * img.width - 0.5, y = v * img.height - 0.5;
    const int x0 = static_cast<int>(std::floor(x)), y0 = static_cast<int>(std::floor(y));
    const double fx = x - x0, fy = y - y0;
    const auto at = [&](int xx, int yy) {
      xx = ((xx % img.width) + img.width) % img.width;
      yy = ((yy % img.height) + img.height) % img.height;
      return static_cast<double>(img.at(xx, yy, c));
    };
    return (at(x0, y0) * (1 - fx) + at(x0 + 1, y0) * fx) * (1 - fy) +
           (at(x0, y0 + 1) * (1 - fx) + at(x0 + 1, y0 + 1) * fx) * fy;
  }
};

struct View {
  int w, h;
  double cam[3];
  double yaw, pitch;
  int floor_tex, wall_tex, ceil_tex, back_tex;
};

Image render(const View& v, const std::vector<Tex>& tex) {
  // Room: x in [-4, 4], y in [0, 3], z in [-6, 10]. Texture scale: one tile per 2 units.
  const double fov = 1.0;  // tan(half horizontal angle)
  Image out(v.w, v.h, 3);
  const double cy = std::cos(v.yaw), sy = std::sin(v.yaw), cp = std::cos(v.pitch), sp = std::sin(v.pitch);
  for (int py = 0; py < v.h; ++py)
    for (int px = 0; px < v.w; ++px) {
      double acc[3] = {0, 0, 0};
      for (int s = 0; s < 4; ++s) {
        const double sx = (px + 0.25 + 0.5 * (s & 1)) / v.w * 2 - 1;
        const double syy = 1 - (py + 0.25 + 0.5 * (s >> 1)) / v.h * 2;
        double d[3] = {sx * fov, syy * fov * v.h / v.w, 1.0};
        // pitch about x, then yaw about y
        const double dy = d[1] * cp + d[2] * sp, dz = -d[1] * sp + d[2] * cp;
        const double dx = d[0] * cy + dz * sy, dz2 = -d[0] * sy + dz * cy;
        const double dir[3] = {dx, dy, dz2};
        double best = 1e30;
        int surf = -1;
        double uu = 0, vv = 0;
        const auto plane = [&](int axis, double value, int id, int ua, int va) {
          if (std::fabs(dir[axis]) < 1e-9) return;
          const double t = (value - v.cam[axis]) / dir[axis];
          if (t <= 1e-6 || t >= best) return;
          const double p[3] = {v.cam[0] + t * dir[0], v.cam[1] + t * dir[1], v.cam[2] + t * dir[2]};
          if (p[0] < -4.001 || p[0] > 4.001 || p[1] < -0.001 || p[1] > 3.001 || p[2] < -6.001 || p[2] > 10.001)
            return;
          best = t;
          surf = id;
          uu = p[ua] / 2.0;
          vv = p[va] / 2.0;
        };
        plane(1, 0.0, 0, 0, 2);   // floor
        plane(1, 3.0, 1, 0, 2);   // ceiling
        plane(0, -4.0, 2, 2, 1);  // left wall
        plane(0, 4.0, 2, 2, 1);   // right wall
        plane(2, 10.0, 3, 0, 1);  // far wall
        plane(2, -6.0, 2, 0, 1);  // near wall
        if (surf < 0) continue;
        const int t = surf == 0 ? v.floor_tex : surf == 1 ? v.ceil_tex : surf == 2 ? v.wall_tex : v.back_tex;
        const double p[3] = {v.cam[0] + best * dir[0], v.cam[1] + best * dir[1], v.cam[2] + best * dir[2]};
        // Two point lights and ambient.
        const double l1 = 1.0 / (1.0 + 0.04 * ((p[0] - 1) * (p[0] - 1) + (p[1] - 2.8) * (p[1] - 2.8) + (p[2] - 2) * (p[2] - 2)));
        const double l2 = 1.0 / (1.0 + 0.06 * ((p[0] + 2) * (p[0] + 2) + (p[1] - 2.8) * (p[1] - 2.8) + (p[2] - 7) * (p[2] - 7)));
        const double light = std::min(1.4, 0.25 + 0.9 * l1 + 0.6 * l2);
        for (int c = 0; c < 3; ++c) acc[c] += tex[t].sample(uu, -vv, c) * light;
      }
      for (int c = 0; c < 3; ++c)
        out.at(px, py, c) = static_cast<uint8_t>(std::clamp(std::lround(acc[c] / 4), 0L, 255L));
    }
  return out;
}

int cmd_views(const std::string& texdir, const std::string& outdir) {
  // Benchmark-set textures only (bench/run_texture.sh extracts them).
  const char* names[] = {"concretefloor1.tga", "ind_wall1.tga",       "metaltechfloor01final.tga",
                         "blocks17_ow.tga",    "metalfloor_wall_15ow.tga", "rock05.tga",
                         "comp_up.tga",        "proto_brik.tga",      "concrete01wetwall.tga",
                         "rusty_pentagrate.tga"};
  std::vector<Tex> tex;
  for (const char* n : names) tex.push_back({rgb_of(vds::enc::load_image(texdir + "/" + n))});
  const View views[] = {
      {240, 180, {0.0, 1.6, -4.0}, 0.0, -0.05, 0, 1, 4, 6},   {240, 180, {-2.5, 1.2, -2.0}, 0.6, 0.0, 3, 7, 0, 2},
      {240, 180, {2.0, 2.2, 0.0}, -0.5, -0.3, 8, 5, 4, 9},    {240, 180, {0.5, 0.8, 5.0}, 2.8, 0.1, 2, 1, 8, 6},
      {240, 180, {-1.0, 1.7, 2.0}, -1.3, -0.15, 0, 3, 2, 7},  {512, 512, {0.0, 1.5, -5.0}, 0.1, -0.1, 2, 7, 4, 6},
      {512, 512, {3.0, 2.5, 1.0}, -0.9, -0.4, 9, 1, 0, 3},    {512, 512, {-3.0, 1.0, 8.0}, 2.4, 0.2, 0, 5, 8, 6},
      {512, 512, {1.0, 1.8, 3.0}, 0.0, 0.35, 3, 4, 7, 1},     {512, 512, {0.0, 0.6, 0.0}, 1.57, -0.05, 8, 3, 2, 9},
  };
  int i = 0;
  for (const View& v : views) {
    const Image img = render(v, tex);
    char name[256];
    std::snprintf(name, sizeof name, "%s/view%02d_%dx%d.png", outdir.c_str(), i++, v.w, v.h);
    vds::enc::save_png(name, img);
    std::printf("%s\n", name);
  }
  return 0;
}

// --- rate-distortion points ------------------------------------------------------

struct Point {
  std::string image, codec;
  int param;
  size_t bytes;
  double bpp, psnr, psnr_y;
};

Image read_ppm(const std::string& path) { return vds::enc::load_image(path, 3); }

struct RdOptions {
  bool quick = false;
  bool anchors = true;
  vds::enc::ImageEncodeOptions enc;
};

int cmd_rd(const std::string& list, const std::string& csv, const RdOptions& ro) {
  const bool quick = ro.quick;
  const auto items = read_list(list);
  std::ofstream out(csv);
  out << "image,codec,param,bytes,bpp,psnr_rgb,psnr_y\n";
  const std::string tmp = tmpdir();
  for (const Item& it : items) {
    const Image src = rgb_of(vds::enc::load_image(it.path));
    const double pixels = static_cast<double>(src.width) * src.height;
    const std::string ppm = tmp + "/src.ppm";
    write_ppm(ppm, src);
    const auto emit = [&](const std::string& codec, int param, size_t bytes, const Image& dec) {
      const double bpp = bytes * 8.0 / pixels;
      out << it.name << "," << codec << "," << param << "," << bytes << "," << bpp << "," << psnr_rgb(src, dec) << ","
          << psnr_luma(src, dec) << "\n";
    };
    const auto t0 = std::chrono::steady_clock::now();
    // libjpeg-turbo anchors: quality ladder, optimised Huffman and arithmetic.
    for (int q = 5; ro.anchors && q <= 98; q += (quick ? 10 : (q < 30 ? 5 : (q < 90 ? 3 : 2)))) {
      for (const char* mode : {"-optimize", "-arithmetic"}) {
        const std::string jpg = tmp + "/a.jpg", dec = tmp + "/a.ppm";
        run("cjpeg " + std::string(mode) + " -quality " + std::to_string(q) + " -outfile " + jpg + " " + ppm);
        run("djpeg -dct int -ppm -outfile " + dec + " " + jpg);
        const size_t bytes = vds::enc::read_file(jpg).size();
        emit(std::string("jpeg") + (mode[1] == 'o' ? "-opt" : "-arith"), q, bytes, read_ppm(dec));
      }
    }
    const auto t1 = std::chrono::steady_clock::now();
    // vds: quantiser index ladder (the quality scale maps onto it).
    for (int qi = 8; qi <= 232; qi += quick ? 16 : 6) {
      const vds::enc::ImageEncodeOptions& o = ro.enc;
      const vds::enc::Planes planes = vds::enc::rgb_to_planes(src, o.chroma);
      const int delta = o.chroma_delta == 999 ? (o.chroma == vds::ChromaFormat::yuv420 ? -16 : -8) : o.chroma_delta;
      const vds::enc::EncodedImage e = vds::enc::encode_planes_at(planes, qi, std::clamp(qi + delta, 0, 255), o);
      const std::vector<uint8_t> stream = vds::enc::image_stream(e);
      const vds::enc::DecodedImage d = vds::enc::decode_stream_image(stream);
      if (d.rgb.pixels != vds::enc::planes_to_rgb(e.recon).pixels)
        throw std::runtime_error("the client shows other pixels than the encoder's reconstruction");
      emit("vds", qi, e.coded_bytes(), d.rgb);
    }
    const auto t2 = std::chrono::steady_clock::now();
    std::fprintf(stderr, "%-28s %4dx%-4d jpeg %.1fs vds %.1fs\n", it.name.c_str(), src.width, src.height,
                 std::chrono::duration<double>(t1 - t0).count(), std::chrono::duration<double>(t2 - t1).count());
    out.flush();
  }
  return 0;
}

// --- Bjontegaard delta rate ----------------------------------------------------------

// Monotone piecewise-cubic Hermite interpolation (Fritsch-Carlson), x ascending.
struct Pchip {
  std::vector<double> x, y, m;
  Pchip(std::vector<double> xs, std::vector<double> ys) : x(std::move(xs)), y(std::move(ys)) {
    const size_t n = x.size();
    m.assign(n, 0);
    std::vector<double> d(n - 1);
    for (size_t i = 0; i + 1 < n; ++i) d[i] = (y[i + 1] - y[i]) / (x[i + 1] - x[i]);
    if (n == 2) {
      m[0] = m[1] = d[0];
      return;
    }
    for (size_t i = 1; i + 1 < n; ++i) {
      if (d[i - 1] * d[i] <= 0) {
        m[i] = 0;
      } else {
        const double w1 = 2 * (x[i + 1] - x[i]) + (x[i] - x[i - 1]), w2 = (x[i + 1] - x[i]) + 2 * (x[i] - x[i - 1]);
        m[i] = (w1 + w2) / (w1 / d[i - 1] + w2 / d[i]);
      }
    }
    const auto end_slope = [](double h0, double h1, double d0, double d1) {
      double s = ((2 * h0 + h1) * d0 - h0 * d1) / (h0 + h1);
      if (s * d0 <= 0) s = 0;
      else if (d0 * d1 <= 0 && std::fabs(s) > std::fabs(3 * d0)) s = 3 * d0;
      return s;
    };
    m[0] = end_slope(x[1] - x[0], x[2] - x[1], d[0], d[1]);
    m[n - 1] = end_slope(x[n - 1] - x[n - 2], x[n - 2] - x[n - 3], d[n - 2], d[n - 3]);
  }
  double operator()(double t) const {
    size_t i = std::upper_bound(x.begin(), x.end(), t) - x.begin();
    i = std::clamp<size_t>(i, 1, x.size() - 1) - 1;
    const double h = x[i + 1] - x[i], s = (t - x[i]) / h;
    const double h00 = (1 + 2 * s) * (1 - s) * (1 - s), h10 = s * (1 - s) * (1 - s), h01 = s * s * (3 - 2 * s),
                 h11 = s * s * (s - 1);
    return h00 * y[i] + h10 * h * m[i] + h01 * y[i + 1] + h11 * h * m[i + 1];
  }
};

// A codec's curve on one image: log10(bpp) as a function of PSNR, limited to
// 0.25..2 bpp (interpolated at the ends).
struct Curve {
  std::vector<double> psnr, logr;
  bool ok = false;
};

constexpr double kBppLo = 0.25, kBppHi = 2.0;

Curve make_curve(std::vector<std::pair<double, double>> pts /* bpp, psnr */) {
  Curve c;
  std::sort(pts.begin(), pts.end());
  // Keep the upper envelope: PSNR strictly increasing with rate.
  std::vector<std::pair<double, double>> mono;
  for (const auto& p : pts)
    if (mono.empty() || p.second > mono.back().second + 1e-9) mono.push_back(p);
  if (mono.size() < 2) return c;
  std::vector<double> lr, ps;
  for (const auto& p : mono) {
    lr.push_back(std::log10(p.first));
    ps.push_back(p.second);
  }
  // PSNR at the range ends, by interpolating PSNR over log-rate.
  const Pchip by_rate(lr, ps);
  const double lo = std::log10(kBppLo), hi = std::log10(kBppHi);
  if (lr.front() > lo + 1e-9 || lr.back() < hi - 1e-9) {
    // The curve does not span the whole range: use what it covers inside it.
  }
  const double a = std::max(lo, lr.front()), b = std::min(hi, lr.back());
  if (b <= a) return c;
  c.psnr.push_back(by_rate(a));
  c.logr.push_back(a);
  for (size_t i = 0; i < lr.size(); ++i)
    if (lr[i] > a + 1e-9 && lr[i] < b - 1e-9) {
      c.psnr.push_back(ps[i]);
      c.logr.push_back(lr[i]);
    }
  c.psnr.push_back(by_rate(b));
  c.logr.push_back(b);
  for (size_t i = 1; i < c.psnr.size(); ++i)
    if (c.psnr[i] <= c.psnr[i - 1]) return c;
  c.ok = c.psnr.size() >= 2;
  return c;
}

// Bjontegaard delta rate of test against anchor: mean log-rate difference
// over the overlapping PSNR interval, as a percentage.
bool bd_rate(const Curve& anchor, const Curve& test, double* out) {
  if (!anchor.ok || !test.ok) return false;
  const double lo = std::max(anchor.psnr.front(), test.psnr.front());
  const double hi = std::min(anchor.psnr.back(), test.psnr.back());
  if (hi - lo < 0.5) return false;
  const Pchip fa(anchor.psnr, anchor.logr), ft(test.psnr, test.logr);
  constexpr int kSteps = 1000;
  double sum = 0;
  for (int i = 0; i <= kSteps; ++i) {
    const double p = lo + (hi - lo) * i / kSteps;
    const double w = (i == 0 || i == kSteps) ? 0.5 : 1.0;
    sum += w * (ft(p) - fa(p));
  }
  *out = (std::pow(10.0, sum / kSteps) - 1.0) * 100.0;
  return true;
}

int cmd_bd(const std::string& csv, const std::string& md, const std::string& plot_csv) {
  std::ifstream f(csv);
  if (!f) throw std::runtime_error("cannot open " + csv);
  std::string line;
  std::getline(f, line);
  // image -> codec -> points (bpp, psnr_rgb, psnr_y)
  std::map<std::string, std::map<std::string, std::vector<std::array<double, 3>>>> data;
  std::vector<std::string> order;
  while (std::getline(f, line)) {
    std::stringstream s(line);
    std::string img, codec, param, bytes, bpp, pr, py;
    std::getline(s, img, ',');
    std::getline(s, codec, ',');
    std::getline(s, param, ',');
    std::getline(s, bytes, ',');
    std::getline(s, bpp, ',');
    std::getline(s, pr, ',');
    std::getline(s, py, ',');
    if (data.find(img) == data.end()) order.push_back(img);
    data[img][codec].push_back({std::stod(bpp), std::stod(pr), std::stod(py)});
  }
  std::ofstream o(md);
  std::ofstream pc(plot_csv);
  pc << "image,codec,bpp,psnr_rgb,psnr_y\n";
  o << "| image | vds vs jpeg-opt (RGB) | vds vs jpeg-arith (RGB) | jpeg-arith vs jpeg-opt (RGB) | vds vs jpeg-opt (Y) |\n";
  o << "|---|---:|---:|---:|---:|\n";
  struct Acc {
    double sum = 0;
    int n = 0;
    void add(double v) {
      sum += v;
      ++n;
    }
    std::string str() const {
      if (n == 0) return "n/a";
      char b[32];
      std::snprintf(b, sizeof b, "%+.1f %%", sum / n);
      return b;
    }
  };
  std::map<std::string, std::array<Acc, 4>> groups;
  for (const std::string& img : order) {
    auto& codecs = data[img];
    const auto curve = [&](const std::string& c, int which) {
      std::vector<std::pair<double, double>> pts;
      for (const auto& p : codecs[c]) pts.push_back({p[0], p[which]});
      return make_curve(pts);
    };
    const Curve opt = curve("jpeg-opt", 1), ari = curve("jpeg-arith", 1), v = curve("vds", 1);
    const Curve opt_y = curve("jpeg-opt", 2), v_y = curve("vds", 2);
    double r[4];
    bool ok[4] = {bd_rate(opt, v, &r[0]), bd_rate(ari, v, &r[1]), bd_rate(opt, ari, &r[2]), bd_rate(opt_y, v_y, &r[3])};
    const std::string group = img.rfind("view", 0) == 0 ? "rendered views" : "textures";
    o << "| " << img;
    for (int i = 0; i < 4; ++i) {
      char b[32];
      if (ok[i]) {
        std::snprintf(b, sizeof b, "%+.1f %%", r[i]);
        groups[group][i].add(r[i]);
        groups["all"][i].add(r[i]);
      } else {
        std::snprintf(b, sizeof b, "n/a");
      }
      o << " | " << b;
    }
    o << " |\n";
    for (const auto& [codec, pts] : codecs)
      for (const auto& p : pts) pc << img << "," << codec << "," << p[0] << "," << p[1] << "," << p[2] << "\n";
  }
  o << "\n| set | images | vds vs jpeg-opt (RGB) | vds vs jpeg-arith (RGB) | jpeg-arith vs jpeg-opt (RGB) | vds vs jpeg-opt (Y) |\n";
  o << "|---|---:|---:|---:|---:|---:|\n";
  for (const char* g : {"textures", "rendered views", "all"}) {
    auto& a = groups[g];
    o << "| " << g << " | " << a[0].n << " | " << a[0].str() << " | " << a[1].str() << " | " << a[2].str() << " | "
      << a[3].str() << " |\n";
  }
  std::printf("all: vds vs jpeg-opt %s, vs jpeg-arith %s (Y: %s); textures %s, views %s\n", groups["all"][0].str().c_str(),
              groups["all"][1].str().c_str(), groups["all"][3].str().c_str(), groups["textures"][0].str().c_str(),
              groups["rendered views"][0].str().c_str());
  return 0;
}

// --- client decode cost ---------------------------------------------------------------

// A .jpg as the client receives it: an images stream of JPEG chunks
// (4096 bytes each, as `vds encode-image --jpeg` writes them); a .vds
// stream as it is.
std::vector<uint8_t> client_stream(const std::vector<uint8_t>& bytes, bool* is_jpeg) {
  *is_jpeg = bytes.size() > 2 && bytes[0] == 0xFF && bytes[1] == 0xD8;
  if (!*is_jpeg) return bytes;
  vds::JpegInfo info;
  if (vds::jpeg_peek_info(bytes.data(), bytes.size(), &info) != vds::Status::ok) throw std::runtime_error("not a JPEG the client decodes");
  vds::StreamHeader h = vds::enc::default_header(vds::StreamMode::images, info.width, info.height);
  h.frame_count = 1;
  h.max_chunk_payload = 4096;
  h.workspace_bytes = static_cast<uint32_t>(vds::Player::jpeg_workspace_bytes(info.width, vds::kClientPlayerConfig));
  vds::enc::StreamWriter w(h);
  for (size_t at = 0; at < bytes.size(); at += 4096)
    w.add_chunk(vds::chunk::kJpeg, std::span(bytes).subspan(at, std::min<size_t>(4096, bytes.size() - at)));
  return w.finish();
}

// Plays a stream through vds::Player (the client's configuration) into an
// RGB565 frame, as the board firmware (firmware_sim/app/bench_texture.cpp)
// does, `n` times.
std::vector<uint16_t> client_rgb565(const std::vector<uint8_t>& stream, int* w, int* h, int n = 1) {
  struct Out {
    std::vector<uint16_t> frame;
    int w = 0, h = 0;
  } out;
  std::vector<uint8_t> ws((1 << 16) + 65536);
  vds::PlayerConfig config = vds::kClientPlayerConfig;
  config.max_chunk_bytes = 1 << 16;
  vds::PlayerCallbacks cb;
  cb.ctx = &out;
  cb.begin_frame = [](void* ctx, uint16_t fw, uint16_t fh) {
    Out& o = *static_cast<Out*>(ctx);
    o.w = fw;
    o.h = fh;
    o.frame.assign(static_cast<size_t>(fw) * fh, 0);
    return true;
  };
  cb.band = [](void* ctx, const vds::PixelRect& r) {
    Out& o = *static_cast<Out*>(ctx);
    for (int row = 0; row < r.h; ++row)
      std::memcpy(&o.frame[static_cast<size_t>(r.y + row) * r.w], r.pixels + row * r.stride, static_cast<size_t>(r.w) * 2);
    return true;
  };
  for (int i = 0; i < n; ++i) {
    vds::Arena arena(ws.data(), ws.size());
    vds::Player player;
    if (player.init(arena, config, cb) != vds::Status::ok) throw std::logic_error("player init");
    vds::Status s = player.feed(stream.data(), stream.size());
    if (s == vds::Status::more_input) s = player.finish();
    if (s != vds::Status::ok || player.frames_shown() != 1)
      throw std::runtime_error(std::string("the client player: ") + vds::status_name(s) + " (" + player.error_detail() + ")");
  }
  *w = out.w;
  *h = out.h;
  return out.frame;
}

int cmd_decode(const std::string& path, int n) {
  bool is_jpeg = false;
  const std::vector<uint8_t> stream = client_stream(vds::enc::read_file(path), &is_jpeg);
  int w = 0, h = 0;
  const std::vector<uint16_t> frame = client_rgb565(stream, &w, &h, n);
  uint32_t checksum = 2166136261u;
  for (uint16_t v : frame) checksum = (checksum ^ v) * 16777619u;
  std::printf("%s %dx%d %zu stream bytes, checksum %08x, player object %zu bytes\n", is_jpeg ? "jpeg" : "vds", w, h,
              stream.size(), checksum, sizeof(vds::Player));
  return 0;
}

int cmd_m4_case(const std::string& in, const std::string& out, int reps) {
  bool is_jpeg = false;
  const std::vector<uint8_t> bytes = client_stream(vds::enc::read_file(in), &is_jpeg);
  int w = 0, h = 0;
  const std::vector<uint16_t> frame = client_rgb565(bytes, &w, &h);
  std::vector<uint8_t> f = {'V', 'T', 'X', '1', static_cast<uint8_t>(is_jpeg ? 1 : 0), static_cast<uint8_t>(reps)};
  const auto u16 = [&](uint32_t v) {
    f.push_back(static_cast<uint8_t>(v));
    f.push_back(static_cast<uint8_t>(v >> 8));
  };
  u16(static_cast<uint32_t>(w));
  u16(static_cast<uint32_t>(h));
  u16(0);
  u16(static_cast<uint32_t>(bytes.size()));
  u16(static_cast<uint32_t>(bytes.size() >> 16));
  f.insert(f.end(), bytes.begin(), bytes.end());
  vds::enc::write_file(out, f);
  std::printf("%s %dx%d %zu bytes host_crc=%08x\n", is_jpeg ? "jpeg" : "vds", w, h, bytes.size(),
              vds::crc32c(reinterpret_cast<const uint8_t*>(frame.data()), frame.size() * 2));
  return 0;
}

int cmd_psnr(const std::string& a, const std::string& b) {
  const Image x = rgb_of(vds::enc::load_image(a)), y = rgb_of(vds::enc::load_image(b));
  std::printf("%.4f\n", psnr_rgb(x, y));
  return 0;
}

int cmd_make_vds(const std::string& in, const std::string& out, double psnr, int slope) {
  const Image src = rgb_of(vds::enc::load_image(in));
  vds::enc::ImageEncodeOptions o;
  o.target_psnr = psnr;
  o.slope = slope;
  const vds::enc::EncodedImage e = vds::enc::encode_image(src, o);
  const std::vector<uint8_t> stream = vds::enc::image_stream(e);
  vds::enc::write_file(out, stream);
  std::printf("%s: %zu bytes coded (%zu stream), RGB PSNR %.2f dB, quantiser %d/%d\n", out.c_str(), e.coded_bytes(),
              stream.size(), e.psnr, e.header.quant_luma, e.header.quant_chroma);
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  try {
    const std::string cmd = argc > 1 ? argv[1] : "";
    if (cmd == "views" && argc == 4) return cmd_views(argv[2], argv[3]);
    if (cmd == "rd" && argc >= 4) {
      RdOptions ro;
      for (int i = 4; i < argc; ++i) {
        const std::string a = argv[i];
        const auto val = [&](const char* key) { return a.substr(std::strlen(key)); };
        if (a == "--quick") ro.quick = true;
        else if (a == "--no-anchors") ro.anchors = false;
        else if (a.rfind("--slope=", 0) == 0) ro.enc.slope = std::stoi(val("--slope="));
        else if (a.rfind("--delta=", 0) == 0) ro.enc.chroma_delta = std::stoi(val("--delta="));
        else if (a.rfind("--lambda=", 0) == 0) ro.enc.lambda_scale = std::stod(val("--lambda="));
        else if (a == "--no-rdo") ro.enc.rdo = false;
        else if (a == "--444") ro.enc.chroma = vds::ChromaFormat::yuv444;
        else throw std::runtime_error("unknown option " + a);
      }
      return cmd_rd(argv[2], argv[3], ro);
    }
    if (cmd == "bd" && argc == 5) return cmd_bd(argv[2], argv[3], argv[4]);
    if (cmd == "decode" && argc == 4) return cmd_decode(argv[2], std::atoi(argv[3]));
    if (cmd == "make-vds" && (argc == 5 || argc == 6))
      return cmd_make_vds(argv[2], argv[3], std::atof(argv[4]), argc == 6 ? std::atoi(argv[5]) : -1);
    if (cmd == "m4-case" && argc == 5) return cmd_m4_case(argv[2], argv[3], std::atoi(argv[4]));
    if (cmd == "psnr" && argc == 4) return cmd_psnr(argv[2], argv[3]);
    if (cmd == "workspace" && argc == 2) {
      std::printf("vds::ImageDecoder: workspace %zu bytes, object %zu bytes (this host)\n",
                  vds::ImageDecoder::kWorkspaceBytes, sizeof(vds::ImageDecoder));
      std::printf("vds::JpegDecoder:  workspace %zu bytes, object %zu bytes (this host)\n",
                  vds::JpegDecoder::kWorkspaceBytes, sizeof(vds::JpegDecoder));
      return 0;
    }
    std::fprintf(stderr, "usage: see the comment at the top of bench/src/texture.cpp\n");
    return 2;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "bench_texture: %s\n", e.what());
    return 1;
  }
}
