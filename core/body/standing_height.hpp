#pragma once
// A body model's standing height for a shape: its highest rest vertex above its lowest. The rest
// pose (SMPL's T-pose) stands upright on straight legs, so this is crown to sole, the height a
// clinic measures (session header `height_m`).
#include <Eigen/Core>

#include "body/smpl_model.hpp"

namespace posefuse::body {

// The standing heights a session header may record (SessionHeader.height_m), metres.
inline constexpr double kMinStandingHeightM = 0.5, kMaxStandingHeightM = 2.5;

struct StandingHeight {
  double height_m = 0;
  // d height / d beta (1 x B) with the same highest and lowest vertices: height is piecewise linear
  // in beta, and this is the piece at beta.
  Eigen::RowVectorXd gradient;
};

// Throws posefuse::Error "beta" when it has more entries than the model has shape directions;
// fewer are zero padded.
StandingHeight standing_height(const SmplModel& model, const Eigen::VectorXd& beta);

}  // namespace posefuse::body
