#include "fit/shape_pose_refiner.hpp"

#include <algorithm>
#include <cmath>
#include <string>
#include <utility>

#include "common/error.hpp"
#include "fit/frame_observation.hpp"
#include "fit/segment_measurements.hpp"

namespace posefuse::fit {

namespace {

// The refiner's priors as ShapeFreedom's linear prior, rows stacked: the 7 segment residuals
// (L(beta) - K) / (s sqrt 7) ~ (L(beta0) + G (beta - beta0) - K) / (s sqrt 7), then beta / (sigma sqrt B).
void add_shape_priors(const ShapeRefinerOptions& options, const SegmentLengths& measured,
                      const ModelSegmentLengths& segment_model, const Eigen::VectorXd& beta0, ShapeFreedom& freedom) {
  const int nb = segment_model.num_betas();
  Eigen::VectorXd start = Eigen::VectorXd::Zero(nb);
  start.head(std::min<Eigen::Index>(nb, beta0.size())) = beta0.head(std::min<Eigen::Index>(nb, beta0.size()));
  const int segments = options.segment_sigma_m > 0 ? kBodySegmentCount : 0;
  const int betas = options.beta_sigma > 0 ? nb : 0;
  freedom.prior_matrix.setZero(segments + betas, nb);
  freedom.prior_target.setZero(segments + betas);
  if (segments > 0) {
    Eigen::MatrixXd gradient;
    const SegmentLengths at_start = segment_model.lengths(start, &gradient);
    const double scale = 1 / (options.segment_sigma_m * std::sqrt(static_cast<double>(kBodySegmentCount)));
    freedom.prior_matrix.topRows(segments) = scale * gradient;
    for (int l = 0; l < segments; ++l)
      freedom.prior_target[l] = scale * (measured[static_cast<size_t>(l)] - at_start[static_cast<size_t>(l)]) +
                                freedom.prior_matrix.row(l).dot(start);
  }
  if (betas > 0)
    freedom.prior_matrix.bottomRows(betas).diagonal().setConstant(
        1 / (options.beta_sigma * std::sqrt(static_cast<double>(nb))));
}

}  // namespace

std::size_t silhouette_pixels_at_border(const DepthFrame& frame, int border_px) {
  std::size_t count = 0;
  for (int row = 0; row < frame.height; ++row) {
    for (int col = 0; col < frame.width; ++col) {
      const bool border =
          row < border_px || col < border_px || row >= frame.height - border_px || col >= frame.width - border_px;
      if (border && frame.body_index[static_cast<std::size_t>(row) * frame.width + col] != kNoBody) ++count;
    }
  }
  return count;
}

ShapePoseRefiner make_depth_shape_refiner(std::shared_ptr<const body::SmplModel> model,
                                          const raycast::DepthCamera& camera, std::vector<CalibrationFrame> frames,
                                          const ShapeRefinerOptions& options) {
  if (!model) throw_invalid("model", "is null");
  FitOptions fit_options = options.fit;
  fit_options.lambda_float = 0;  // III-B: data, bg, bgJoint, limit
  fit_options.lambda_imu = 0;
  validate(fit_options);
  // K_l of eq. 18: the mean measurements of the frames' skeletons (as estimate_rough_shape).
  SegmentLengths measured{};
  for (const CalibrationFrame& f : frames) {
    const SegmentLengths one = measure_segments(f.skeleton.positions_K);
    for (int l = 0; l < kBodySegmentCount; ++l)
      measured[static_cast<size_t>(l)] += one[static_cast<size_t>(l)] / static_cast<double>(frames.size());
  }
  const ModelSegmentLengths segment_model(*model, options.head_above_skull_base_m);
  auto shared_frames = std::make_shared<const std::vector<CalibrationFrame>>(std::move(frames));
  return [model = std::move(model), &camera, shared_frames, fit_options, options, measured, segment_model](
             std::size_t frame_index, const Eigen::VectorXd& beta0, const Eigen::VectorXd& theta0) {
    if (frame_index >= shared_frames->size())
      throw_invalid("fine_tuning.frame_index", std::to_string(frame_index) + " is past the " +
                                                   std::to_string(shared_frames->size()) + " calibration depth frames");
    const CalibrationFrame& calibration = (*shared_frames)[frame_index];
    const std::string field = "calibration_frames[" + std::to_string(frame_index) + "]";
    validate(calibration.frame, camera);
    const std::size_t at_border = silhouette_pixels_at_border(calibration.frame, options.border_px);
    if (at_border > options.max_border_pixels)
      throw Error(ErrorCode::kFailedPrecondition, field + ".body_index",
                  std::to_string(at_border) + " silhouette pixels lie within " + std::to_string(options.border_px) +
                      " px of the image edge: the subject is not fully in view");
    const FrameObservation observation =
        prepare_observation(calibration.frame, camera, calibration.skeleton.positions_K, fit_options);
    ShapeFreedom freedom = options.freedom;
    add_shape_priors(options, measured, segment_model, beta0, freedom);
    FrameFitter fitter(model, body::PoseLayout::full_body(), camera.intrinsics(), fit_options);
    const FitResult fit = fitter.fit_shape_and_pose(observation, theta0, beta0, freedom);
    const double energy = fit.energy.total();
    if (!(energy <= options.max_energy))
      throw Error(ErrorCode::kFailedPrecondition, "fine_tuning.energy",
                  "the model fits " + field + " only to E = " + std::to_string(energy) + " (limit " +
                      std::to_string(options.max_energy) +
                      "): the subject is not in the controlled pose or not the skeleton's person");
    return ShapePoseFit{fit.beta, fit.theta, energy};
  };
}

}  // namespace posefuse::fit
