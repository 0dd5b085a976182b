#pragma once
// The shape a measured standing height implies when the recording gives nothing else of the
// subject (the personalisation refused, docs/fitting.md, "Personalisation"): the most probable
// betas under the population prior beta ~ N(0, beta_sigma^2) per beta, the fine tuning's own
// (ShapeRefinerOptions::beta_sigma), given the model's standing height (body/standing_height.hpp)
// equal to the measured one within height_sigma_m. With one measurement that is the smallest
// beta (in the prior's units) of the right height: the change goes to the shape directions in
// proportion to how much each moves the height.
#include <Eigen/Core>

#include "body/smpl_model.hpp"

namespace posefuse::fit {

struct HeightShapeOptions {
  // A stadiometer reads to a few millimetres; posture and what the subject stands in add about as
  // much. Far below what one beta moves the height (several cm), so the result hardly depends on it.
  double height_sigma_m = 0.01;
  double beta_sigma = 1.0;
};

// Throws posefuse::Error "height_m" outside 0.5 .. 2.5 m or not finite, "height_shape_options.*"
// for a sigma that is not positive.
Eigen::VectorXd shape_from_height(const body::SmplModel& model, double height_m,
                                  const HeightShapeOptions& options = {});

}  // namespace posefuse::fit
