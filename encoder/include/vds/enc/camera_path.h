// vds encoder: camera paths for walkthroughs, as text files other tools can
// write.
//
// A path: one line per frame, "frame x y z yaw_deg pitch_deg", frames 0, 1,
// 2, ... in order, in the scene's units (Quake: Z up, yaw 0 = +X, 90 = +Y,
// pitch positive up, within [-90, 90]). Lines starting with '#' are
// comments; "# hfov DEG" and "# fps N" set the horizontal field of view
// (default 90) and the frame rate (default 20). Blank lines are ignored.
//
// Keyframes: one line per key, "time_s x y z yaw_deg pitch_deg", times
// rising; the same comments. interpolate_keyframes samples them at the
// frame rate with a Catmull-Rom spline through the keys (positions and
// angles alike; each yaw taken the short way round from the previous one),
// so the camera passes every key and moves smoothly between them.
#pragma once
#include <string>
#include <vector>

namespace vds::enc {

struct CameraPose {
  double x = 0, y = 0, z = 0;
  double yaw_deg = 0, pitch_deg = 0;
};

struct CameraPath {
  double hfov_deg = 90;
  double fps = 20;
  std::vector<CameraPose> frames;
};

// The most frames or keys a file may hold.
constexpr size_t kMaxPathFrames = 1u << 20;

// Throws std::runtime_error "NAME: what (line N)".
CameraPath read_camera_path(const std::string& text, const std::string& name);
std::string write_camera_path(const CameraPath& p);

struct CameraKey {
  double time_s = 0;
  CameraPose pose;
};
struct CameraKeys {
  double hfov_deg = 90;
  double fps = 20;
  std::vector<CameraKey> keys;
};
CameraKeys read_camera_keys(const std::string& text, const std::string& name);
// Frames at 0, 1/fps, 2/fps, ... up to the last key's time.
CameraPath interpolate_keyframes(const CameraKeys& k);

}  // namespace vds::enc
