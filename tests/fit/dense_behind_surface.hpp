#pragma once
// The first implementation of D_3D, kept as the reference for the query-time search in
// fit/behind_surface_map: every voxel of the grid is classified and an exact squared Euclidean
// distance transform (Felzenszwalb-Huttenlocher, separable over x, y, z) gives each voxel its
// squared grid distance to the nearest behind voxel. Used by tests and the preprocessing bench.
#include <cstdint>
#include <vector>

#include "fit/behind_surface_map.hpp"

namespace posefuse::fit::testing {

// Squared distance in voxel units from every voxel (index (k * ny + j) * nx + i) to the nearest
// behind voxel; infinity when no voxel is behind.
std::vector<double> dense_behind_distance2(const BehindSurfaceMap& map);

}  // namespace posefuse::fit::testing
