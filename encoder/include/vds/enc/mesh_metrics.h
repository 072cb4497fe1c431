// vds encoder: distances between two surfaces for rate-distortion figures:
// points sampled uniformly on each surface (plus its vertices), each point's
// distance to the other surface found through a uniform grid of triangles,
// in the manner of Metro (Cignoni, Rocchini, Scopigno, 1998).
#pragma once
#include <cstddef>
#include <cstdint>

#include "vds/enc/mesh_import.h"

namespace vds::enc {

struct SurfaceDistance {
  double max_ab = 0;     // largest distance from a point of A to B
  double max_ba = 0;
  double hausdorff = 0;  // symmetric: max(max_ab, max_ba)
  double rms = 0;        // root mean square over the samples of both directions
  double mean = 0;       // mean over the samples of both directions
};

// `samples` points per surface (area-weighted, deterministic for a seed)
// plus every vertex. Distances in model units.
SurfaceDistance surface_distance(const Mesh& a, const Mesh& b, size_t samples = 50000, uint32_t seed = 1);

}  // namespace vds::enc
