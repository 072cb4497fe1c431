// vds encoder: camera path and keyframe files (vds/enc/camera_path.h).
#include "vds/enc/camera_path.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <stdexcept>

namespace vds::enc {

namespace {

constexpr size_t kMaxLine = 1024;

[[noreturn]] void fail(const std::string& name, const std::string& what, size_t line) {
  throw std::runtime_error(name + ": " + what + " (line " + std::to_string(line) + ")");
}

// Whitespace-separated numbers of a line: exactly `n` of them, finite.
std::vector<double> numbers(const std::string& line, size_t n, const std::string& name, size_t line_no) {
  std::vector<double> v;
  const char* p = line.c_str();
  while (*p != '\0') {
    while (*p == ' ' || *p == '\t' || *p == '\r') ++p;
    if (*p == '\0') break;
    char* end = nullptr;
    const double d = std::strtod(p, &end);
    if (end == p || !(end[0] == '\0' || end[0] == ' ' || end[0] == '\t' || end[0] == '\r'))
      fail(name, "a value that is not a number", line_no);
    if (!std::isfinite(d)) fail(name, "a value that is not finite", line_no);
    if (v.size() == n) fail(name, "more than " + std::to_string(n) + " values", line_no);
    v.push_back(d);
    p = end;
  }
  if (v.size() != n) fail(name, std::to_string(v.size()) + " values where " + std::to_string(n) + " are needed", line_no);
  return v;
}

CameraPose pose_of(const std::vector<double>& v, const std::string& name, size_t line_no) {
  CameraPose p{v[1], v[2], v[3], v[4], v[5]};
  if (std::fabs(p.x) > 1e7 || std::fabs(p.y) > 1e7 || std::fabs(p.z) > 1e7) fail(name, "a position beyond 1e7 units", line_no);
  if (std::fabs(p.yaw_deg) > 1e6) fail(name, "a yaw beyond 1e6 degrees", line_no);
  if (p.pitch_deg < -90 || p.pitch_deg > 90) fail(name, "a pitch outside [-90, 90] degrees", line_no);
  return p;
}

// Walks the lines of `text`: comments set hfov and fps; every other
// non-blank line goes to `row` with its number.
template <class Row>
void lines(const std::string& text, const std::string& name, double* hfov, double* fps, Row row) {
  size_t at = 0, line_no = 0;
  while (at < text.size()) {
    size_t nl = text.find('\n', at);
    if (nl == std::string::npos) nl = text.size();
    ++line_no;
    if (nl - at > kMaxLine) fail(name, "a line longer than 1024 bytes", line_no);
    const std::string line = text.substr(at, nl - at);
    at = nl + 1;
    for (unsigned char c : line)
      if ((c < 0x20 && c != '\t' && c != '\r') || c == 0x7F) fail(name, "a control byte", line_no);
    size_t first = line.find_first_not_of(" \t\r");
    if (first == std::string::npos) continue;
    if (line[first] == '#') {
      double v = 0;
      char tail = 0;
      if (std::sscanf(line.c_str() + first, "# hfov %lf %c", &v, &tail) == 1) {
        if (!(v > 1 && v < 179)) fail(name, "a horizontal field of view outside (1, 179) degrees", line_no);
        *hfov = v;
      } else if (std::sscanf(line.c_str() + first, "# fps %lf %c", &v, &tail) == 1) {
        if (!(v >= 1 && v <= 240)) fail(name, "a frame rate outside [1, 240]", line_no);
        *fps = v;
      }
      continue;
    }
    row(line, line_no);
  }
}

// A value as written in a message: an integer as one, else as %g.
std::string number_text(double v) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "%.15g", v);
  return buf;
}

// Catmull-Rom through p1 (t = 0) and p2 (t = 1), p0 and p3 their neighbours.
double catmull_rom(double p0, double p1, double p2, double p3, double t) {
  return 0.5 * ((2 * p1) + (-p0 + p2) * t + (2 * p0 - 5 * p1 + 4 * p2 - p3) * t * t + (-p0 + 3 * p1 - 3 * p2 + p3) * t * t * t);
}

}  // namespace

CameraPath read_camera_path(const std::string& text, const std::string& name) {
  CameraPath p;
  lines(text, name, &p.hfov_deg, &p.fps, [&](const std::string& line, size_t line_no) {
    const std::vector<double> v = numbers(line, 6, name, line_no);
    if (v[0] != static_cast<double>(p.frames.size()))
      fail(name, "frame " + number_text(v[0]) + " where frame " + std::to_string(p.frames.size()) + " comes next",
           line_no);
    if (p.frames.size() == kMaxPathFrames) fail(name, "more than " + std::to_string(kMaxPathFrames) + " frames", line_no);
    p.frames.push_back(pose_of(v, name, line_no));
  });
  if (p.frames.empty()) throw std::runtime_error(name + ": no frames");
  return p;
}

std::string write_camera_path(const CameraPath& p) {
  std::string out = "# vds camera path: frame x y z yaw_deg pitch_deg\n";
  char buf[160];
  std::snprintf(buf, sizeof buf, "# hfov %.9g\n# fps %.9g\n", p.hfov_deg, p.fps);
  out += buf;
  for (size_t i = 0; i < p.frames.size(); ++i) {
    const CameraPose& c = p.frames[i];
    std::snprintf(buf, sizeof buf, "%zu %.17g %.17g %.17g %.17g %.17g\n", i, c.x, c.y, c.z, c.yaw_deg, c.pitch_deg);
    out += buf;
  }
  return out;
}

CameraKeys read_camera_keys(const std::string& text, const std::string& name) {
  CameraKeys k;
  lines(text, name, &k.hfov_deg, &k.fps, [&](const std::string& line, size_t line_no) {
    const std::vector<double> v = numbers(line, 6, name, line_no);
    if (v[0] < 0 || v[0] > 86400) fail(name, "a time outside [0, 86400] s", line_no);
    if (!k.keys.empty() && !(v[0] > k.keys.back().time_s)) fail(name, "a time that does not rise", line_no);
    if (k.keys.size() == kMaxPathFrames) fail(name, "more than " + std::to_string(kMaxPathFrames) + " keys", line_no);
    k.keys.push_back({v[0], pose_of(v, name, line_no)});
  });
  if (k.keys.size() < 2) throw std::runtime_error(name + ": fewer than two keys");
  if (k.keys.back().time_s * k.fps >= static_cast<double>(kMaxPathFrames))
    throw std::runtime_error(name + ": more than " + std::to_string(kMaxPathFrames) + " frames at " +
                             std::to_string(k.fps) + " frames/s");
  return k;
}

CameraPath interpolate_keyframes(const CameraKeys& k) {
  if (k.keys.size() < 2) throw std::invalid_argument("interpolate_keyframes: fewer than two keys");
  // Yaws unwrapped: each within half a turn of the previous one.
  std::vector<CameraPose> keys;
  for (const CameraKey& key : k.keys) keys.push_back(key.pose);
  for (size_t i = 1; i < keys.size(); ++i) {
    double d = std::fmod(keys[i].yaw_deg - keys[i - 1].yaw_deg, 360.0);
    if (d > 180) d -= 360;
    if (d < -180) d += 360;
    keys[i].yaw_deg = keys[i - 1].yaw_deg + d;
  }
  CameraPath p;
  p.hfov_deg = k.hfov_deg;
  p.fps = k.fps;
  const double t0 = k.keys.front().time_s, t1 = k.keys.back().time_s;
  const size_t frames = static_cast<size_t>(std::floor((t1 - t0) * k.fps + 1e-9)) + 1;
  size_t seg = 0;
  for (size_t f = 0; f < frames; ++f) {
    const double t = t0 + static_cast<double>(f) / k.fps;
    while (seg + 2 < k.keys.size() && t > k.keys[seg + 1].time_s) ++seg;
    const double a = k.keys[seg].time_s, b = k.keys[seg + 1].time_s;
    const double u = std::clamp((t - a) / (b - a), 0.0, 1.0);
    const CameraPose& p0 = keys[seg > 0 ? seg - 1 : seg];
    const CameraPose& p1 = keys[seg];
    const CameraPose& p2 = keys[seg + 1];
    const CameraPose& p3 = keys[seg + 2 < keys.size() ? seg + 2 : seg + 1];
    CameraPose c;
    c.x = catmull_rom(p0.x, p1.x, p2.x, p3.x, u);
    c.y = catmull_rom(p0.y, p1.y, p2.y, p3.y, u);
    c.z = catmull_rom(p0.z, p1.z, p2.z, p3.z, u);
    c.yaw_deg = catmull_rom(p0.yaw_deg, p1.yaw_deg, p2.yaw_deg, p3.yaw_deg, u);
    c.pitch_deg = std::clamp(catmull_rom(p0.pitch_deg, p1.pitch_deg, p2.pitch_deg, p3.pitch_deg, u), -90.0, 90.0);
    // Yaw back into [0, 360).
    c.yaw_deg = std::fmod(c.yaw_deg, 360.0);
    if (c.yaw_deg < 0) c.yaw_deg += 360;
    if (c.yaw_deg >= 360) c.yaw_deg = 0;  // -1e-17 + 360 rounds to 360
    p.frames.push_back(c);
  }
  return p;
}

}  // namespace vds::enc
