#pragma once
// Surface normals of the point cloud (paper 2, II-H): PCA of the neighbours within a Chebyshev
// window in the image and a Euclidean radius in K; the third principal component, oriented
// towards the camera (the origin of K).
#include <Eigen/Core>
#include <cstdint>
#include <optional>
#include <vector>

#include "fit/depth_frame.hpp"
#include "fit/zone_sampling.hpp"

namespace posefuse::fit {

struct NormalParams {
  int window_radius_px = 5;      // Chebyshev distance in pixels (paper: 5)
  float max_distance_m = 0.05f;  // Euclidean distance in K (paper: 0.05 m)
  // Fewer neighbours (centre included) than this gives no normal: a plane fit needs at least 3
  // and a handful more keeps single-row slivers and noise from giving a confident direction.
  int min_neighbours = 6;
};

// Unit normals towards the camera; pixels without enough neighbours are not valid.
using NormalMap = VectorImage;

// Throws posefuse::Error (field "normal_params.*") for a non-positive window, radius or count.
void validate(const NormalParams& params);

// Normal at one cloud pixel; nullopt when the pixel is not in the cloud or has too few neighbours.
std::optional<Eigen::Vector3f> estimate_normal_at(const PointCloud& cloud, int col, int row,
                                                  const NormalParams& params = {});

// Normals at the sampled pixels only, in sample order: all the fitter needs (the data term
// uses the N_s samples), about 0.6 us per sample instead of 11 ms for every pixel of a body frame.
std::vector<std::optional<Eigen::Vector3f>> estimate_sample_normals(const PointCloud& cloud,
                                                                    const std::vector<DepthSample>& samples,
                                                                    const NormalParams& params = {});

// Normals at every cloud pixel (for tests and pictures; the fitter needs only the samples').
NormalMap estimate_normals(const PointCloud& cloud, const NormalParams& params = {});

}  // namespace posefuse::fit
