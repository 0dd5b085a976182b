#pragma once
// The body the simulator renders is never exactly a member of the fitted model family (issue 4,
// "model mismatch"): the fitted template is subdivided (every triangle into four, skinning
// weights and shape directions carried to the new vertices by averaging), and clothing and
// soft tissue push the surface out along its rest normals by a smooth random field of up to
// about 2 cm, loosest at the torso and the sleeves. The joints stay the template's: the joint
// regressor reads unchanged "ghost" copies of the template's vertices that no face uses.
//
// The render model also carries what the colour camera needs per vertex: a material (skin,
// shirt, trousers, shoes, hair) and, on each forearm, the distance from the elbow along the
// elbow -> wrist line in the rest pose, from which the strap band (paper 1, II-H) is coloured.
#include <cstdint>
#include <memory>
#include <vector>

#include <Eigen/Core>
#include <Eigen/Geometry>

#include "body/smpl_model.hpp"

namespace posefuse::sim {

enum class Material : std::uint8_t { kSkin = 0, kShirt, kTrousers, kShoes, kHair };

struct ClothingOptions {
  bool enabled = true;               // false: the subdivided template without offsets
  int subdivisions = 1;              // 0..2 levels of 1 -> 4 triangle splits
  double torso_offset_m = 0.02;      // largest outward offset per region (shirt on the torso)
  double sleeve_offset_m = 0.02;     // upper arms (sleeves)
  double trousers_offset_m = 0.015;  // legs
  double skin_offset_m = 0.004;      // forearms, hands, head, neck: soft tissue only
  double wavelength_m = 0.25;        // spatial scale of the folds
};

// kInvalidArgument naming the field.
void validate(const ClothingOptions& options);

struct RenderModel {
  std::shared_ptr<body::SmplModel> model;  // subdivided, offset; ghost vertices at the end
  int surface_vertices = 0;                // vertices 0..surface_vertices-1 carry the faces
  std::vector<Material> material;          // per vertex
  // Per vertex: distance (m) from the elbow along the rest elbow -> wrist line for vertices
  // that follow a forearm, NaN elsewhere; forearm_arm: 0 left, 1 right, -1 neither.
  std::vector<float> forearm_coordinate_m;
  std::vector<std::int8_t> forearm_arm;
};

// `betas` shape the rest mesh used for the forearm coordinate and the normals.
RenderModel make_render_model(const body::SmplModel& fitted, const Eigen::VectorXd& betas,
                              const ClothingOptions& options, std::uint64_t seed);

// One level of midpoint subdivision of an SMPL-format model (exposed for tests).
body::SmplModel subdivide(const body::SmplModel& model);

}  // namespace posefuse::sim
