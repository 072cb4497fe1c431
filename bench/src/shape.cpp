// Benchmark driver for the shape a walkthrough client draws its views onto
// (vds/enc/scene_shape.h): how far its depth strays from the scene's, seen
// from the cameras of a tour, at each decimation tolerance.
//
//   bench_shape SCENE TOUR EVERY TOLERANCE_M...
//
// For every EVERY-th camera of TOUR both the scene and its shape are drawn
// (240x180, one sample a pixel, depth only) and each pixel the scene covers
// is counted as: empty (the shape shows nothing there: a hole), through
// (the shape's surface lies more than the tolerance plus 1 % of the depth
// behind the scene's: a crack it sees through), in front (as far the other
// way: what a coarser surface hides), or within. One markdown row per
// tolerance on stdout.
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <stdexcept>
#include <string>
#include <vector>

#include "vds/enc/camera_path.h"
#include "vds/enc/scene.h"
#include "vds/enc/scene_render.h"
#include "vds/enc/scene_shape.h"
#include "vds/enc/stream_writer.h"

namespace {

std::vector<std::vector<float>> depths(const vds::enc::Scene& s, const vds::enc::CameraPath& path, int every) {
  vds::enc::RenderOptions ro;
  ro.supersample = 1;
  const vds::enc::SceneRenderer r(s, {}, ro);
  std::vector<std::vector<float>> out;
  for (size_t f = 0; f < path.frames.size(); f += static_cast<size_t>(every))
    out.push_back(r.render(path.frames[f], path.hfov_deg).depth);
  return out;
}

}  // namespace

int main(int argc, char** argv) {
  if (argc < 5) {
    std::fprintf(stderr, "usage: bench_shape SCENE TOUR EVERY TOLERANCE_M...\n");
    return 2;
  }
  try {
    const vds::enc::Scene scene = vds::enc::load_scene(argv[1]);
    const std::vector<uint8_t> text = vds::enc::read_file(argv[2]);
    const vds::enc::CameraPath path = vds::enc::read_camera_path(std::string(text.begin(), text.end()), argv[2]);
    const int every = std::atoi(argv[3]);
    if (every < 1 || path.frames.empty()) throw std::runtime_error("EVERY must be 1 or more, and the tour not empty");
    const std::vector<std::vector<float>> truth = depths(scene, path, every);
    std::printf("| tolerance | triangles drawn | pixels | empty | through | in front | within |\n|---:|---:|---:|---:|---:|---:|---:|\n");
    for (int a = 4; a < argc; ++a) {
      const double tol_m = std::atof(argv[a]);
      vds::enc::ShapeOptions o;
      o.tolerance = tol_m / scene.metres_per_unit;
      const vds::enc::Scene shape = vds::enc::simplify_shape(scene, o);
      const std::vector<std::vector<float>> d = depths(shape, path, every);
      size_t pixels = 0, empty = 0, through = 0, front = 0, within = 0;
      for (size_t k = 0; k < truth.size(); ++k)
        for (size_t i = 0; i < truth[k].size(); ++i) {
          const float t = truth[k][i], s = d[k][i];
          if (!std::isfinite(t)) continue;
          ++pixels;
          const double margin = o.tolerance + 0.01 * t;
          if (!std::isfinite(s)) ++empty;
          else if (s > t + margin) ++through;
          else if (s < t - margin) ++front;
          else ++within;
        }
      std::printf("| %.4g m | %zu | %zu | %zu | %zu | %zu | %.4f %% |\n", tol_m, shape.triangles(), pixels, empty, through, front,
                  100.0 * static_cast<double>(within) / static_cast<double>(pixels ? pixels : 1));
      std::fflush(stdout);
    }
  } catch (const std::exception& e) {
    std::fprintf(stderr, "bench_shape: %s\n", e.what());
    return 1;
  }
  return 0;
}
