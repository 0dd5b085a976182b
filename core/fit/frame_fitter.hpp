#pragma once
// Per-frame fit of the body model to one depth frame (paper 2, II-D to II-J): Levenberg-
// Marquardt over the pose theta and the data-term correspondences U together (eq. 15-16),
// with the correspondences eliminated by a Schur complement (fit/schur_system.hpp), moved by
// mesh walking after each accepted step (II-I) and by the discrete update between iterations
// (II-J, fit/correspondence_update.hpp). The bg point set U_bg is re-selected at every iteration
// from the model's visible contour (Embree ray casts) and then kept for the iteration's trial
// steps; which of its points are outside the silhouette (bg) or in front of the surface (float),
// and their D_2D / D_3D targets, are re-evaluated at each trial pose, so a trial is judged on the
// energy it really has (with the sets' members fixed).
//
// Energy (eq. 4): data + lambda_bg bg + lambda_bgJoint bgJoint + lambda_float float
// + lambda_limit limit + lambda_imu imu, each term a residual block of fit/residual_blocks.hpp.
// The shape beta is fixed during the per-frame fit (personalised beforehand, paper 2 III);
// fit_shape_and_pose() frees it for the fine shape tuning of III-B: the LM parameters are then
// (theta, beta_free, U), every residual block gets shape columns d r / d beta_free (analytic,
// BodyEvaluator's vertex and joint shape Jacobians) and the free betas a soft bound.
//
// A FrameFitter owns its evaluators, Embree scene and work buffers: one per worker thread; fit()
// reuses them, so after the first frame the loop allocates little (see docs/fitting.md).
#include <Eigen/Core>
#include <memory>
#include <span>
#include <vector>

#include "body/body_evaluator.hpp"
#include "body/surface.hpp"
#include "body/surface_pose_jacobians.hpp"
#include "fit/correspondence_update.hpp"
#include "fit/fit_options.hpp"
#include "fit/frame_observation.hpp"
#include "fit/residual_blocks.hpp"
#include "fit/schur_system.hpp"
#include "raycast/mesh_scene.hpp"

namespace posefuse::fit {

// The 16 joints of the bgJoint term (eq. 7): the upper body's joints without the hands (orbs).
inline constexpr int kBgJointCount = 16;
inline constexpr int kBgJoints[kBgJointCount] = {
    body::kPelvis,      body::kLeftHip,    body::kRightHip,     body::kSpine1,
    body::kSpine2,      body::kSpine3,     body::kNeck,         body::kLeftCollar,
    body::kRightCollar, body::kHead,       body::kLeftShoulder, body::kRightShoulder,
    body::kLeftElbow,   body::kRightElbow, body::kLeftWrist,    body::kRightWrist};

// Energy of each term of eq. 4, weights included (E = sum of all).
struct EnergyTerms {
  double data = 0, bg = 0, bg_joint = 0, float_term = 0, limit = 0, imu = 0;
  double shape = 0;  // fit_shape_and_pose only: the betas' bound and prior (ShapeFreedom)
  double total() const { return data + bg + bg_joint + float_term + limit + imu + shape; }
};

enum class FitStatus {
  kConverged,      // an accepted step lowered E by less than min_relative_decrease, or no step could
  kMaxIterations,  // stopped after max_iterations LM iterations
};
const char* fit_status_name(FitStatus status);

struct FitResult {
  Eigen::VectorXd theta;
  Eigen::VectorXd beta;                             // the shape: as given to fit(), or fitted by fit_shape_and_pose()
  std::vector<body::SurfacePoint> correspondences;  // nu_i, one per observation sample
  EnergyTerms energy;                               // at theta (point sets selected at theta)
  EnergyTerms initial_energy;                       // at the start pose, after the first correspondence update
  int iterations = 0;                               // LM iterations (one linearisation each)
  int accepted_steps = 0;
  int rejected_steps = 0;  // trial steps that raised the energy (gamma was raised)
  FitStatus status = FitStatus::kMaxIterations;
};

// Which shape parameters fit_shape_and_pose() frees (paper 2, III-B).
struct ShapeFreedom {
  std::vector<int> free_betas;  // indices into beta; empty: all of the model's betas
  // Soft bound |beta_b| <= max_abs_beta (ShapeBoundResidual, weight lambda_limit / B_free; its
  // energy is counted in EnergyTerms::shape). The rough shape keeps the same range.
  double max_abs_beta = 3.0;
  // Optional linear prior on the whole beta (B = the model's betas), counted in EnergyTerms::shape:
  // r = prior_matrix * beta - prior_target (k x B and k; empty: none). One frame of a straight-armed
  // pose does not pin every shape direction (where the elbow lies along a straight arm); the
  // personalisation's refiner puts the camera skeleton's segment lengths here.
  Eigen::MatrixXd prior_matrix;
  Eigen::VectorXd prior_target;
};

class FrameFitter {
 public:
  // Throws posefuse::Error for a null or invalid model, invalid intrinsics or options.
  FrameFitter(std::shared_ptr<const body::SmplModel> model, body::PoseLayout layout,
              const raycast::DepthIntrinsics& intrinsics, const FitOptions& options = {});

  // Fits theta from theta0 with the shape beta held fixed, and the pose DOFs `held_dofs` (indices
  // into the layout) held at theta0's values. Throws posefuse::Error for an invalid observation
  // (see validate(FrameObservation)), a theta0 of the wrong size or not finite ("theta"), a beta
  // that does not fit the model ("beta"), or a held DOF out of range or repeated ("held_dofs").
  FitResult fit(const FrameObservation& observation, const Eigen::VectorXd& theta0, const Eigen::VectorXd& beta,
                std::span<const int> held_dofs = {});

  // Paper 2, III-B: fits theta, the free betas and the correspondences together from (theta0,
  // beta0). The other betas stay at beta0's values. Errors as fit(), plus "shape_freedom.free_betas"
  // (an index out of range or repeated) and "shape_freedom.max_abs_beta" (not positive).
  FitResult fit_shape_and_pose(const FrameObservation& observation, const Eigen::VectorXd& theta0,
                               const Eigen::VectorXd& beta0, const ShapeFreedom& freedom = {});

  // Energy of eq. 4 at theta with correspondences found by the discrete update from scratch (the
  // fit's starting energy; lets a caller compare poses without fitting).
  EnergyTerms energy(const FrameObservation& observation, const Eigen::VectorXd& theta, const Eigen::VectorXd& beta);

  const FitOptions& options() const { return options_; }
  const body::PoseLayout& layout() const { return layout_; }

 private:
  struct SilhouettePoint {
    int index;  // vertex (bg) or joint (bgJoint)
    SilhouetteResidual block;
  };
  struct BehindPoint {
    int vertex;
    BehindResidual block;
  };

  void clear_shape_freedom() {
    free_betas_.clear();
    prior_matrix_.resize(0, 0);
    prior_target_.resize(0);
  }
  // The LM loop; the pose DOFs `held` (ascending) keep theta0's values.
  FitResult run(const FrameObservation& observation, const Eigen::VectorXd& theta0, const Eigen::VectorXd& beta0,
                std::span<const int> held = {});
  void set_up_blocks(const FrameObservation& observation);
  void pose_model(const Eigen::VectorXd& theta, const Eigen::VectorXd& beta);
  // Shape fixed: the accepted trial (trial_eval_ evaluated with kPoseOnRequest, trial_surface_)
  // becomes the current model; the same state as pose_model() at the trial's (theta, beta).
  void adopt_trial();
  // The LM parameters x = (theta, beta_free) and back.
  int num_parameters() const { return layout_.size() + static_cast<int>(free_betas_.size()); }
  void split(const Eigen::VectorXd& x, Eigen::VectorXd& theta, Eigen::VectorXd& beta) const;
  // FitOptions::project_steps_onto_limits: the trial's limited pose DOFs clamped to their range
  // widened by limit_projection_margin_rad (or, for a DOF further out at x, to no further than x).
  void project_onto_limits(const Eigen::VectorXd& x, Eigen::VectorXd& trial_x) const;
  // d joints / d x (72 x P): the pose Jacobian alone when the shape is fixed.
  const Eigen::MatrixXd& joint_jacobian() const;
  // d vertex(i) / d x into the 3 x P block `out` (zeroed first).
  void vertex_jacobian(int i, Eigen::Ref<Eigen::Matrix3Xd> out) const;
  void init_correspondences(const FrameObservation& observation);
  void update_correspondences(const FrameObservation& observation, int iteration);
  // Chooses U_bg (H, the bg weight) and counts Q (the float weight) at the current pose.
  void select_point_sets(const FrameObservation& observation);
  // The bg, float and bgJoint blocks of the chosen sets at the pose of `eval`.
  void build_blocks(const body::BodyEvaluator& eval, const FrameObservation& observation);
  // eval_'s vertex pose Jacobians for the vertices linearise() uses: the correspondences' corners,
  // the 1-rings of those whose normal Jacobian needs them (SurfacePoseJacobians::normal_needs_ring,
  // after its reset()) and the bg and float points of build_blocks() (pose_model evaluates with
  // kPoseOnRequest).
  void compute_used_vertex_jacobians();
  // Fills the residual vector and pose / uv Jacobians at the current state; returns per-term energy.
  EnergyTerms linearise(const FrameObservation& observation, const Eigen::VectorXd& theta, const Eigen::VectorXd& beta);
  EnergyTerms energy_at(const FrameObservation& observation, const body::BodyEvaluator& eval,
                        const body::BodySurface& surface, const std::vector<body::SurfacePoint>& correspondences,
                        const Eigen::VectorXd& theta, const Eigen::VectorXd& beta);
  double shape_bound_energy(const Eigen::VectorXd& beta) const;

  std::shared_ptr<const body::SmplModel> model_;
  body::PoseLayout layout_;
  raycast::DepthIntrinsics intrinsics_;
  FitOptions options_;
  body::BodyEvaluator eval_, trial_eval_;
  body::BodySurface surface_, trial_surface_;
  raycast::MeshScene scene_;
  DiscreteCorrespondenceUpdate discrete_;
  SchurSystem system_;
  body::SurfacePoseJacobians surface_jacobians_;  // of eval_ / surface_, reset at each linearisation
  // D_3D voxel classifications of the current observation: float points of successive trial
  // poses and iterations query neighbouring voxels (about 3x cheaper than uncached queries).
  BehindSurfaceCache behind_cache_;

  // Per-frame state.
  std::vector<DataResidual> data_;
  std::vector<ForearmDirectionResidual> imu_;
  LimitResidual limit_;
  // Shape fit (III-B): the free betas (empty: shape fixed) and their bound.
  std::vector<int> free_betas_;
  ShapeBoundResidual shape_bound_;
  Eigen::MatrixXd prior_matrix_;  // k x B, k = 0 without a prior
  Eigen::VectorXd prior_target_;
  std::vector<SilhouettePoint> bg_, bg_joint_;
  std::vector<BehindPoint> float_;
  std::vector<body::SurfacePoint> correspondences_, trial_correspondences_;
  double bg_weight_ = 0, float_weight_ = 0;

  // Work space.
  Eigen::MatrixXd jacobian_;
  Eigen::VectorXd residual_;
  std::vector<UvJacobian> uv_jacobian_;
  Eigen::Matrix3Xd point_jacobian_;
  Eigen::MatrixXd data_jacobian_;         // 6 x N (+ free betas)
  Eigen::MatrixXd packed_data_jacobian_;  // 6 x N, the first face_columns().size() used
  Eigen::Matrix3Xd contour_points_;
  std::vector<int> contour_vertices_, selected_;
  std::vector<char> used_;  // per vertex, within compute_used_vertex_jacobians()
  std::vector<int> used_vertices_;
  std::vector<raycast::ClosestPoint> hits_;
  std::vector<body::SurfacePoint> hit_points_;
  Eigen::MatrixXd joint_jacobian_;       // 72 x P, shape fit only
  Eigen::MatrixXd data_shape_jacobian_;  // 6 x B
  Eigen::VectorXd free_beta_values_;
  Eigen::VectorXd step_, trial_x_, trial_theta_, trial_beta_;
  std::vector<Eigen::Vector2d> uv_step_;
};

}  // namespace posefuse::fit
