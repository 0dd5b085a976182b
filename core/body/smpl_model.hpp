#pragma once
// SMPL's data layout (Loper et al. 2015, as used by paper 2, II-B).
//
// A model is a rest mesh in SMPL's canonical frame (metres; y up, x towards the subject's left,
// z towards the subject's front), plus linear shape directions, optional pose-corrective
// directions, a joint regressor, skinning weights over SMPL's 24 joints and triangle faces.
// The same struct holds the built-in template (body/template_generator.hpp) and a real SMPL
// model read from .npz (body/smpl_npz.hpp); validate() is the single gate both go through.
#include <Eigen/Core>
#include <Eigen/SparseCore>
#include <array>
#include <string>
#include <vector>

namespace posefuse::body {

inline constexpr int kNumJoints = 24;
// SMPL pose-corrective features: (R_j - I) row-major for joints 1..23.
inline constexpr int kNumPoseFeatures = 9 * (kNumJoints - 1);

// SMPL joint order; the index is the joint id used everywhere in core/body.
enum Joint : int {
  kPelvis = 0,
  kLeftHip,
  kRightHip,
  kSpine1,
  kLeftKnee,
  kRightKnee,
  kSpine2,
  kLeftAnkle,
  kRightAnkle,
  kSpine3,
  kLeftFoot,
  kRightFoot,
  kNeck,
  kLeftCollar,
  kRightCollar,
  kHead,
  kLeftShoulder,
  kRightShoulder,
  kLeftElbow,
  kRightElbow,
  kLeftWrist,
  kRightWrist,
  kLeftHand,
  kRightHand,
};

// SMPL's kinematic tree: parent of each joint (-1 for the root). A parent always has a lower id.
inline constexpr std::array<int, kNumJoints> kSmplParents = {-1, 0, 0, 0,  1,  2,  3,  4,  5,  6,  7,  8,
                                                             9,  9, 9, 12, 13, 14, 16, 17, 18, 19, 20, 21};

// SMPL's joint names, in joint order.
const std::array<const char*, kNumJoints>& smpl_joint_names();

struct SmplModel {
  // Rest vertices, 3 x V.
  Eigen::Matrix3Xd v_template;
  // Shape directions: row 3*i+c is coordinate c of vertex i; one column per beta. (3V x B)
  Eigen::MatrixXd shapedirs;
  // Pose-corrective directions, 3V x 207, or empty (0 columns) when the model has none.
  Eigen::MatrixXd posedirs;
  // Joint regressor, 24 x V: rest joints = J_regressor * v_shaped^T.
  Eigen::SparseMatrix<double, Eigen::RowMajor> J_regressor;
  // Skinning weights, V x 24, rows sum to 1.
  Eigen::SparseMatrix<double, Eigen::RowMajor> weights;
  // Kinematic tree (parent per joint); must equal kSmplParents.
  std::array<int, kNumJoints> parents = kSmplParents;
  // Triangles, counter-clockwise seen from outside (outward normals), 3 x F.
  Eigen::Matrix3Xi faces;

  int num_vertices() const { return static_cast<int>(v_template.cols()); }
  int num_betas() const { return static_cast<int>(shapedirs.cols()); }
  int num_faces() const { return static_cast<int>(faces.cols()); }
  bool has_posedirs() const { return posedirs.cols() > 0; }
};

// Throws posefuse::Error naming the array and the value for any inconsistency: sizes,
// non-finite numbers, face indices out of range, weights that are negative or do not sum
// to one, a kinematic tree other than SMPL's.
void validate(const SmplModel& model);

// The joint with the largest skinning weight at a vertex: the bone that carries it.
int dominant_joint(const SmplModel& model, int vertex);

}  // namespace posefuse::body
