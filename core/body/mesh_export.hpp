#pragma once
// Export of a posed mesh (OBJ, ASCII PLY) and of a skeleton, for inspection in a mesh viewer.
//
// Skeleton text format, one joint per line after a comment header:
//   # posefuse skeleton v1: index name parent x y z (metres)
//   0 pelvis -1 0.000000 0.980000 0.000000
#include <Eigen/Core>
#include <array>
#include <ostream>
#include <string>

#include "body/smpl_model.hpp"

namespace posefuse::body {

void write_obj(std::ostream& out, const Eigen::Matrix3Xd& vertices, const Eigen::Matrix3Xi& faces);
void write_ply(std::ostream& out, const Eigen::Matrix3Xd& vertices, const Eigen::Matrix3Xi& faces);
void write_skeleton(std::ostream& out, const Eigen::Matrix3Xd& joints, const std::array<int, kNumJoints>& parents);

// Writes to a file chosen by extension (.obj or .ply); throws posefuse::Error naming the path.
void write_mesh_file(const std::string& path, const Eigen::Matrix3Xd& vertices, const Eigen::Matrix3Xi& faces);
void write_skeleton_file(const std::string& path, const Eigen::Matrix3Xd& joints,
                         const std::array<int, kNumJoints>& parents);

}  // namespace posefuse::body
