#include "fit/shape_pose_refiner.hpp"

#include <cmath>
#include <string>
#include <utility>

#include "common/error.hpp"
#include "fit/frame_observation.hpp"
#include "fit/segment_measurements.hpp"

namespace posefuse::fit {

std::size_t silhouette_pixels_at_border(const DepthFrame& frame, int border_px) {
  std::size_t count = 0;
  for (int row = 0; row < frame.height; ++row) {
    for (int col = 0; col < frame.width; ++col) {
      const bool border = row < border_px || col < border_px || row >= frame.height - border_px ||
                          col >= frame.width - border_px;
      if (border && frame.body_index[static_cast<std::size_t>(row) * frame.width + col] != kNoBody) ++count;
    }
  }
  return count;
}

ShapePoseRefiner make_depth_shape_refiner(std::shared_ptr<const body::SmplModel> model, const raycast::DepthCamera& camera,
                                          std::vector<CalibrationFrame> frames, const ShapeRefinerOptions& options) {
  if (!model) throw_invalid("model", "is null");
  FitOptions fit_options = options.fit;
  fit_options.lambda_float = 0;  // III-B: data, bg, bgJoint, limit
  fit_options.lambda_imu = 0;
  validate(fit_options);
  // K_l of eq. 18: the mean measurements of the frames' skeletons (as estimate_rough_shape).
  SegmentLengths measured{};
  for (const CalibrationFrame& f : frames) {
    const SegmentLengths one = measure_segments(f.skeleton.positions_K);
    for (int l = 0; l < kBodySegmentCount; ++l) measured[static_cast<size_t>(l)] += one[static_cast<size_t>(l)] / static_cast<double>(frames.size());
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
    if (options.segment_sigma_m > 0) {
      // (L(beta) - K) / s ~ (L(beta0) + G (beta - beta0) - K) / s = A beta - t.
      Eigen::MatrixXd gradient;
      const SegmentLengths at_beta0 = segment_model.lengths(beta0, &gradient);
      const double scale = 1 / (options.segment_sigma_m * std::sqrt(static_cast<double>(kBodySegmentCount)));
      freedom.prior_matrix = scale * gradient;
      freedom.prior_target.resize(kBodySegmentCount);
      for (int l = 0; l < kBodySegmentCount; ++l)
        freedom.prior_target[l] = scale * (measured[static_cast<size_t>(l)] - at_beta0[static_cast<size_t>(l)]) +
                                  freedom.prior_matrix.row(l).dot(beta0);
    }
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
