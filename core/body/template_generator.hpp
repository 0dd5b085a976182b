#pragma once
// posefuse's own body template in SMPL format (the official SMPL files may not be
// redistributed). Generated deterministically at run time from a few body dimensions.
//
// Construction (template_geometry.cpp): a single closed mesh swept along the skeleton in the
// SMPL T-pose. A torso tube of elliptic rings (20 vertices) splits at the crotch into two leg
// tubes (12) ending in feet; two side openings at the shoulders continue as arm tubes (12) that
// end in round hand orbs (paper 2, II-B); the top ring continues as the neck (10) and an
// ellipsoidal head (12). Rings are joined by zipper strips, ends by fans, so the mesh is a closed,
// oriented 2-manifold of genus 0 by construction (checked in tests). About 1,000 vertices.
// Canonical frame as SMPL: metres, y up, x to the subject's left, z to the front; the floor is
// y = 0 and the body is centred on x = 0.
//
// Every vertex position is an affine function of BodyDimensions, so each shape direction is
// exactly the difference between the meshes of two dimension sets, and joint positions and the
// measures of the table in template_shape_directions() change exactly linearly with beta.
#include <array>
#include <memory>

#include "body/smpl_model.hpp"

namespace posefuse::body {

enum class Sex { kMale, kFemale };

// Lengths in metres between SMPL joints in the T-pose (legs vertical, arms along x).
struct BodyDimensions {
  Sex sex = Sex::kMale;
  double ankle_height = 0.08;     // floor -> ankle
  double shin = 0.41;             // ankle -> knee
  double thigh = 0.40;            // knee -> hip
  double hip_drop = 0.09;         // hip joints below the pelvis joint
  double hip_half_width = 0.085;  // pelvis -> hip, sideways
  double pelvis_to_spine1 = 0.11, spine1_to_spine2 = 0.13, spine2_to_spine3 = 0.07;
  double spine3_to_neck = 0.20;
  double neck_to_head = 0.10;
  double collar_side = 0.075, collar_up = 0.14;  // spine3 -> collar
  double collar_to_shoulder = 0.105;             // along x, collar and shoulder at one height
  double upper_arm = 0.28, forearm = 0.25;
  double hip_extra_width = 0;       // added to the half width of the lower torso rings
  double shoulder_extra_width = 0;  // added to the half width of the upper torso rings
  double torso_girth = 1.0;         // scale of the torso cross-sections
  double limb_girth = 1.0;          // scale of arm and leg cross-sections
  double head_scale = 1.0;          // scale of the head and of neck -> head
};

BodyDimensions default_dimensions(Sex sex);

inline constexpr int kTemplateNumBetas = 10;

// What one unit of each template beta does. `measure` names the joint distance it changes.
struct ShapeDirectionInfo {
  const char* name;
  const char* description;
};
const std::array<ShapeDirectionInfo, kTemplateNumBetas>& template_shape_directions();

// The dimensions with beta applied (beta 0, stature, is a uniform scale about the floor point
// and is not expressed in dimensions; see make_template).
BodyDimensions apply_shape_direction(const BodyDimensions& base, int direction, double amount);

// Geometry of one dimension set: rest vertices, faces, SMPL joints, and the end points of the
// bone each joint drives (used for the skinning weights).
struct TemplateGeometry {
  Eigen::Matrix3Xd vertices;
  Eigen::Matrix3Xi faces;
  Eigen::Matrix3Xd joints;     // 3 x 24
  Eigen::Matrix3Xd bone_ends;  // 3 x 24: joint j drives the segment joints(j) -> bone_ends(j)
};
TemplateGeometry build_template_geometry(const BodyDimensions& dimensions);

// The full model: mesh, 10 shape directions, skinning weights, joint regressor, no posedirs.
std::shared_ptr<SmplModel> make_template(Sex sex);

// make_template(sex) built once per process and shared (it is deterministic): what every
// session's fit starts from, without rebuilding it per session.
std::shared_ptr<const SmplModel> shared_template(Sex sex);

}  // namespace posefuse::body
