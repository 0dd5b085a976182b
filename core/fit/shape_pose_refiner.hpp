#pragma once
// Paper 2, III-B "fine shape tuning with shape & pose fitting" as a ShapePoseRefiner for
// fit::personalise: on one calibration depth frame of the controlled pose, the LM fitter
// (FrameFitter::fit_shape_and_pose) searches the correspondences U, the shape beta and the 48-DOF
// full-body pose theta together, starting from the rough shape (III-A) and the pose built from
// that frame's camera skeleton. Terms as the paper: data, bg, bgJoint and limit (float and imu
// off), plus a soft bound on the betas (ShapeBoundResidual, ours).
//
// Beside the paper: priors keeping the 7 segment measurements near the camera skeleton's and the
// betas near the population mean (ShapeRefinerOptions::segment_sigma_m, beta_sigma).
//
// Refusals (posefuse::Error, FAILED_PRECONDITION):
//  - "calibration_frames[i].body_index": the silhouette touches the image border (the subject is
//    not fully in view, so the bg term would pull the model into the cut-off body);
//  - "fine_tuning.energy": the fit ends above max_energy (the subject is not in the controlled
//    pose the start assumes, or not the person of the skeleton): the rough shape is no worse.
// The rough-shape step (estimate_rough_shape) has already refused frames not in the pose or
// with joints out of view before the refiner is called.
#include <cstddef>
#include <memory>
#include <vector>

#include "body/smpl_model.hpp"
#include "fit/depth_frame.hpp"
#include "fit/fit_options.hpp"
#include "fit/frame_fitter.hpp"
#include "fit/personalisation.hpp"
#include "fit/tracked_skeleton.hpp"
#include "raycast/depth_camera.hpp"

namespace posefuse::fit {

struct ShapeRefinerOptions {
  // Fit parameters (paper 2 IV-C defaults); lambda_float and lambda_imu are ignored (set to 0:
  // III-B uses data, bg, bgJoint and limit only). The shape needs more iterations than a
  // tracked frame (ours: 60), and the tracking's stopping rules (1 mm joint motion, 1e-5
  // relative decrease) ended shape fits after 7 iterations, before the shape had settled (E 1.04
  // instead of 0.93 after 17): ours 0.1 mm and 1e-6. The silhouette's edge tolerance stays at
  // pixel centres (0.7 px), not the pose fit's 2 px: the girth betas (hip width, torso and limb
  // girth) rest on the silhouette's width, which a 2 px dead zone leaves free by about 1.5 cm a
  // side (on an exact render a girth beta ended 0.54 off instead of within 0.08), and the priors
  // below were chosen with 0.7.
  FitOptions fit = [] {
    FitOptions o;
    o.max_iterations = 60;
    o.min_joint_step_m = 1e-4;
    o.min_relative_decrease = 1e-6;
    o.silhouette_edge_px = 0.7;
    return o;
  }();
  ShapeFreedom freedom;  // all betas, |beta| <= 3 (its prior is set by the refiner)
  // Segment prior (ours): the 7 measurements of III-A (eq. 18) of the fitted shape are kept near
  // the camera skeleton's (mean over the refiner's frames) with this scale, metres, as the
  // residuals (L_l(beta) - K_l) / (sigma sqrt(7)), linearised at beta0. One frame of the
  // controlled pose leaves directions of beta almost free (where the elbow lies along a straight
  // arm; stature against torso and legs), and the data and bg terms of a real frame are not
  // exactly minimal at the true shape: without it the fit of a rendered frame from a shape 0.3 off
  // ended with stature 1.2 and legs 1.5 off. 0.04 m keeps that in check while letting the depth
  // correct skeleton biases (tests/fit/shape_fit_test.cpp, population prior off: a 4 cm arm bias
  // was halved; with 0.02 m it stayed). <= 0: no prior (the paper's III-B).
  double segment_sigma_m = 0.04;
  double head_above_skull_base_m = 0.09;  // the model's Head for ankleToHead (as RoughShapeOptions)
  // Shape prior (ours): beta ~ N(0, beta_sigma^2) per beta, as the residuals beta / (beta_sigma
  // sqrt(B)); the template's betas, like SMPL's, describe the population around beta = 0. With the
  // simulator's noisy frames (depth noise, body-index shift, biased skeleton) one frame let stature, torso
  // and legs run to the bound of 3 against each other; bench_fig4 (docs/benchmarks.md) chose 1.0
  // with segment_sigma_m = 0.04 over either alone. It costs accuracy on an exact, noise-free
  // frame (tests/fit/shape_fit_test.cpp). <= 0: no prior.
  double beta_sigma = 1.0;
  // Silhouette pixels allowed within border_px of the image edge before "not fully in view".
  int border_px = 2;
  std::size_t max_border_pixels = 10;
  // Above this final energy (eq. 4, the III-B terms) the fit is refused (ours).
  double max_energy = 50.0;
};

// One calibration frame: the depth frame (silhouette = the subject) and its camera skeleton.
struct CalibrationFrame {
  DepthFrame frame;
  TrackedSkeleton skeleton;
};

// The refiner for personalise(model, skeletons, camera, refiner): frame_index indexes `frames`,
// which must be the frames whose skeletons personalise() gets, in the same order. The camera must
// outlive the refiner. Throws posefuse::Error "model" (null).
ShapePoseRefiner make_depth_shape_refiner(std::shared_ptr<const body::SmplModel> model,
                                          const raycast::DepthCamera& camera, std::vector<CalibrationFrame> frames,
                                          const ShapeRefinerOptions& options = {});

// Number of silhouette pixels within border_px of the image edge.
std::size_t silhouette_pixels_at_border(const DepthFrame& frame, int border_px);

}  // namespace posefuse::fit
