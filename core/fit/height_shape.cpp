#include "fit/height_shape.hpp"

#include <cmath>
#include <string>

#include "body/standing_height.hpp"
#include "common/error.hpp"
#include "common/number_text.hpp"

namespace posefuse::fit {

Eigen::VectorXd shape_from_height(const body::SmplModel& model, double height_m, const HeightShapeOptions& options) {
  if (!std::isfinite(height_m) || height_m < body::kMinStandingHeightM || height_m > body::kMaxStandingHeightM)
    throw_invalid("height_m", "is " + std::to_string(height_m) + " m, must be " +
                                  fixed_text(body::kMinStandingHeightM, 1) + ".." +
                                  fixed_text(body::kMaxStandingHeightM, 1) + " m");
  if (!(options.height_sigma_m > 0)) throw_invalid("height_shape_options.height_sigma_m", "must be positive");
  if (!(options.beta_sigma > 0)) throw_invalid("height_shape_options.beta_sigma", "must be positive");
  // Minimises ((h(beta) - height) / s_h)^2 + |beta / s_b|^2 with h linearised at beta (g its
  // gradient): beta = s_b^2 g^T (height - h + g beta) / (s_h^2 + s_b^2 |g|^2). The highest and
  // lowest vertices may change with beta, so it is repeated until they do not.
  Eigen::VectorXd beta = Eigen::VectorXd::Zero(model.num_betas());
  const double prior = options.beta_sigma * options.beta_sigma;
  for (int pass = 0; pass < 5; ++pass) {
    const body::StandingHeight h = body::standing_height(model, beta);
    const double residual = height_m - h.height_m + h.gradient.dot(beta);
    const Eigen::VectorXd next = prior * h.gradient.transpose() * residual /
                                 (options.height_sigma_m * options.height_sigma_m + prior * h.gradient.squaredNorm());
    const bool settled = (next - beta).norm() < 1e-9;
    beta = next;
    if (settled) break;
  }
  return beta;
}

}  // namespace posefuse::fit
