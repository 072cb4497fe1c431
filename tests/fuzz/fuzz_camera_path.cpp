// libFuzzer: camera path and keyframe files (vds/enc/camera_path.h), which
// `vds path` and `vds render` read from other tools. The first byte picks
// the reader. Invariants: no crash, sanitizer report or hang; a refusal is a
// std::runtime_error naming the input; an accepted path writes back to a
// file that reads to the same frames; interpolated keyframes stay finite,
// with pitch inside [-90, 90] and yaw inside [0, 360).
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <cstdlib>
#include <cstring>
#include <stdexcept>
#include <string>

#include "vds/enc/camera_path.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  if (size < 1) return 0;
  const std::string text(reinterpret_cast<const char*>(data + 1), size - 1);
  try {
    if (data[0] & 1) {
      const vds::enc::CameraKeys k = vds::enc::read_camera_keys(text, "input");
      if (k.keys.back().time_s * k.fps > 20000) return 0;  // keep each run short
      const vds::enc::CameraPath p = vds::enc::interpolate_keyframes(k);
      for (const auto& c : p.frames)
        if (!std::isfinite(c.x) || !std::isfinite(c.y) || !std::isfinite(c.z) || c.pitch_deg < -90 || c.pitch_deg > 90 ||
            !(c.yaw_deg >= 0 && c.yaw_deg < 360))
          abort();
    } else {
      const vds::enc::CameraPath p = vds::enc::read_camera_path(text, "input");
      const vds::enc::CameraPath q = vds::enc::read_camera_path(vds::enc::write_camera_path(p), "again");
      if (q.frames.size() != p.frames.size() || q.hfov_deg != p.hfov_deg || q.fps != p.fps) abort();
      for (size_t i = 0; i < p.frames.size(); ++i)
        if (q.frames[i].x != p.frames[i].x || q.frames[i].yaw_deg != p.frames[i].yaw_deg) abort();
    }
  } catch (const std::runtime_error& e) {
    if (std::strncmp(e.what(), "input: ", 7) != 0) abort();
  }
  return 0;
}
