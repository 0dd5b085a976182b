#pragma once
// Model personalisation of paper 2, section III, as one call: the rough shape from the camera
// skeleton's measurements (III-A, fit/rough_shape.hpp), then the fine tuning of shape and pose
// together on one full-body depth frame of the controlled pose (III-B: 48-DOF layout, data, bg,
// bgJoint and limit terms, LM over beta, theta and the correspondences).
//
// The fine tuning needs the Levenberg-Marquardt fitter (FrameFitter, built separately), so it is
// a seam here: the caller passes a ShapePoseRefiner that runs that fitter with the shape free on
// the chosen calibration frame's depth data. Without one, the result is the rough shape and says
// so (fine_tuned = false).
#include <Eigen/Core>
#include <cstddef>
#include <functional>
#include <memory>
#include <optional>
#include <vector>

#include "body/smpl_model.hpp"
#include "fit/rough_shape.hpp"
#include "fit/segment_measurements.hpp"
#include "fit/skeleton_pose_init.hpp"

namespace posefuse::fit {

struct ShapePoseFit {
  Eigen::VectorXd beta;   // model.num_betas()
  Eigen::VectorXd theta;  // body::PoseLayout::full_body()
  double energy = 0;      // final E of the fit (eq. 4 with the III-B terms)
};

// Fits shape and pose to calibration frame `frame_index` (the caller's depth frame of that index),
// starting from beta0 (rough shape) and theta0 (full-body pose built from that frame's skeleton).
using ShapePoseRefiner =
    std::function<ShapePoseFit(std::size_t frame_index, const Eigen::VectorXd& beta0, const Eigen::VectorXd& theta0)>;

struct PersonalisationOptions {
  RoughShapeOptions rough;
  SkeletonInitOptions init;  // for the full-body starting pose
  // Calibration frame for the fine tuning; default the middle one.
  std::optional<std::size_t> fine_tune_frame;
};

struct Personalisation {
  RoughShapeResult rough;
  std::size_t fine_tune_frame = 0;
  Eigen::VectorXd initial_theta;  // full-body pose the fine tuning started from
  bool fine_tuned = false;
  ShapePoseFit fine;                 // valid when fine_tuned
  SegmentLengths segment_lengths{};  // the 7 measurements of the final shape

  const Eigen::VectorXd& beta() const { return fine_tuned ? fine.beta : rough.beta; }
};

// Throws what estimate_rough_shape throws (the pose and view checks), "personalisation_options.
// fine_tune_frame" for an index past the frames, and kInternal "fine_tuning.beta" /
// "fine_tuning.theta" when the refiner returns wrong sizes or non-finite values.
Personalisation personalise(std::shared_ptr<const body::SmplModel> model,
                            const std::vector<TrackedSkeleton>& calibration_frames, const raycast::DepthCamera* camera,
                            const ShapePoseRefiner& refiner, const PersonalisationOptions& options = {});

}  // namespace posefuse::fit
