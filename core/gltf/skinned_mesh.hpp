#pragma once
// The personalised rest mesh in glTF's skinning layout: SMPL's canonical frame (metres, y up),
// at most 4 joints per vertex (glTF's JOINTS_0 / WEIGHTS_0).
#include <Eigen/Core>
#include <cstdint>
#include <vector>

#include "body/smpl_model.hpp"

namespace posefuse::gltf {

struct SkinnedMesh {
  Eigen::Matrix3Xf positions;                             // v_shaped = v_template + shapedirs beta, 3 x V
  Eigen::Matrix3Xf normals;                               // unit, area weighted, 3 x V
  std::vector<std::uint32_t> indices;                     // the faces' corners, 3 per face
  Eigen::Matrix<std::uint8_t, 4, Eigen::Dynamic> joints;  // 4 joint ids per vertex
  Eigen::Matrix4Xf weights;                               // sum exactly 1 in float; unused slots: joint 0, weight 0
  Eigen::Matrix3Xd rest_joints;                           // J(beta) = J_regressor v_shaped, 3 x 24
  int dropped_influences = 0;                             // vertices with more than 4 joints (the smallest dropped)
};

// Each vertex keeps its 4 largest SMPL weights, renormalised. `beta` has the model's size.
SkinnedMesh skinned_mesh(const body::SmplModel& model, const Eigen::VectorXd& beta);

}  // namespace posefuse::gltf
