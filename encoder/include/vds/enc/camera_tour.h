// vds encoder: a camera tour through a scene's spawn points (`vds path
// SCENE`), for walkthroughs: holds, pans and dollies along routes that keep
// the camera out of walls.
//
// The route between two stops is found on a grid of free space (cells of
// TourOptions::cell map units whose centre has no triangle within `radius`
// in 26 directions; neighbours joined where a ray between centres is free),
// by A* with a cost that grows with height above the floor (so the camera
// walks rather than flies); the cells' path is then shortened to the
// fewest straight legs whose sideways-offset rays (vds/enc/scene_rays.h)
// cross nothing, and its corners rounded where the rounding stays clear.
// At each stop the camera holds, then pans towards the side with the
// longer sight lines, turns to face its route, and then dollies to the next
// stop at `speed`, easing in and out, looking where it goes.
#pragma once
#include <cstddef>
#include <string>
#include <vector>

#include "vds/enc/camera_path.h"
#include "vds/enc/scene.h"
#include "vds/enc/scene_rays.h"

namespace vds::enc {

// Lengths and speeds in Quake map units (1/32 m), scaled to the scene's own
// units by Scene::metres_per_unit.
struct TourOptions {
  size_t frames = 600;
  double fps = 20;
  double hfov_deg = 90;
  double speed = 200;       // map units per second while dollying
  double eye_height = 26;   // above a spawn point's origin (Quake's view height)
  double radius = 12;       // the camera keeps this far from every triangle
  double cell = 24;         // the free-space grid
  double hold_s = 1.0;      // still at each stop
  double pan_s = 2.5;       // then a pan of pan_deg towards the more open side
  double pan_deg = 90;
};

struct TourReport {
  std::vector<size_t> stops;       // spawn points visited, in order
  std::vector<size_t> unreachable; // spawn points no route reached
  double length = 0;               // map units travelled
  double min_clearance = 0;        // the least distance to a triangle along the 26 directions, over all frames
};

// A scene without spawn points is toured from the centre of its bounds.
// Throws std::runtime_error when no spawn point's eye position is clear of
// the geometry.
CameraPath make_tour(const Scene& s, const SceneRays& rays, const TourOptions& o, TourReport* report = nullptr);

}  // namespace vds::enc
