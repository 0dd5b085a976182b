#pragma once
// Writes the skinned body and its animation as one binary glTF 2.0 file (.glb) with tinygltf.
//
// Scene: a node "body" holding the mesh and its skin (at the scene's root with no transform, as
// glTF's skinning asks), and a node "camera_to_gltf" holding glTF_from_K whose child is SMPL's
// joint tree in K (24 nodes named as smpl_joint_names(), in SMPL order). Joint j's translation is
// its rest offset J_j - J_parent (the pelvis: its position in K, animated), its rotation the
// local rotation R_parent^T R_j (animated, one LINEAR channel per joint); its inverse bind matrix
// is translate(-J_j), so a vertex skinned to j lands at R_j (v_rest - J_j) + p_j as in SMPL.
// Keyframe times are seconds from the first fitted frame, whose camera-clock time is the
// animation's extras.first_frame_camera_time_s. The nodes' own transforms are the first frame's pose.
#include <Eigen/Geometry>
#include <ostream>

#include "gltf/body_animation.hpp"
#include "gltf/skinned_mesh.hpp"

namespace posefuse::gltf {

// glTF's axes from the OpenSim ground G (x forward, y up, z right): glTF has y up and the
// subject facing +z, so x_glTF = -z_G (the subject's left), y_glTF = y_G, z_glTF = x_G.
Eigen::Matrix3d gltf_from_ground();

struct GltfSummary {
  int frames = 0, vertices = 0, faces = 0;
};

// Throws posefuse::Error (kInternal) "glb" when tinygltf fails to write.
GltfSummary write_gltf_body(const SkinnedMesh& mesh, const BodyAnimation& animation,
                            const Eigen::Isometry3d& gltf_from_K, std::ostream& out);

}  // namespace posefuse::gltf
