// For the walkthrough planners' tests: a tour of an installed map and, per
// frame, the triangles its ground truth shows with the pixels each covers
// (one sample a pixel: visibility only).
#pragma once
#include <cstdint>
#include <string>
#include <utility>
#include <vector>

#include "vds/enc/camera_tour.h"
#include "vds/enc/scene.h"
#include "vds/enc/scene_rays.h"
#include "vds/enc/scene_render.h"

namespace vds::test {

struct TourVisibility {
  vds::enc::Scene scene;
  vds::enc::CameraPath path;
  std::vector<std::vector<std::pair<uint32_t, uint32_t>>> visible;  // (triangle, pixels), by triangle
};

inline TourVisibility tour_visibility(const std::string& map, size_t frames) {
  TourVisibility t;
  t.scene = vds::enc::load_scene(map);
  const vds::enc::SceneRays rays(t.scene);
  vds::enc::TourOptions to;
  to.frames = frames;
  t.path = vds::enc::make_tour(t.scene, rays, to);
  vds::enc::RenderOptions ro;
  ro.supersample = 1;
  ro.max_aniso = 1;
  const vds::enc::SceneRenderer r(t.scene, {}, ro);
  for (const auto& pose : t.path.frames) {
    t.visible.push_back(vds::enc::visible_triangles(r.render(pose, t.path.hfov_deg)));
  }
  return t;
}

}  // namespace vds::test
