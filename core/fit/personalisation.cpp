#include "fit/personalisation.hpp"

#include <string>

#include "common/error.hpp"

namespace posefuse::fit {

Personalisation personalise(std::shared_ptr<const body::SmplModel> model, const std::vector<TrackedSkeleton>& frames,
                            const raycast::DepthCamera* camera, const ShapePoseRefiner& refiner,
                            const PersonalisationOptions& options) {
  if (!model) throw_invalid("model", "is null");
  Personalisation p;
  p.rough = estimate_rough_shape(*model, frames, camera, options.rough);
  p.fine_tune_frame = options.fine_tune_frame.value_or(frames.size() / 2);
  if (p.fine_tune_frame >= frames.size())
    throw_invalid("personalisation_options.fine_tune_frame", std::to_string(p.fine_tune_frame) + " is past the " +
                                                                 std::to_string(frames.size()) + " calibration frames");
  const body::PoseLayout layout = body::PoseLayout::full_body();
  const SkeletonPoseInitializer init(model, layout, p.rough.beta, options.init);
  p.initial_theta = init.initialise(frames[p.fine_tune_frame], Eigen::VectorXd()).theta;
  const ModelSegmentLengths lengths(*model, options.rough.head_above_skull_base_m);
  if (refiner) {
    p.fine = refiner(p.fine_tune_frame, p.rough.beta, p.initial_theta);
    if (p.fine.beta.size() != model->num_betas() || !p.fine.beta.allFinite())
      throw Error(ErrorCode::kInternal, "fine_tuning.beta",
                  "the refiner returned " + std::to_string(p.fine.beta.size()) + " betas (model has " +
                      std::to_string(model->num_betas()) + ") or non-finite values");
    if (p.fine.theta.size() != layout.size() || !p.fine.theta.allFinite())
      throw Error(ErrorCode::kInternal, "fine_tuning.theta",
                  "the refiner returned " + std::to_string(p.fine.theta.size()) + " pose parameters (full body has " +
                      std::to_string(layout.size()) + ") or non-finite values");
    p.fine_tuned = true;
  }
  p.segment_lengths = lengths.lengths(p.beta());
  return p;
}

}  // namespace posefuse::fit
