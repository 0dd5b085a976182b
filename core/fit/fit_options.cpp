#include "fit/fit_options.hpp"

#include <cmath>
#include <string>

#include "common/error.hpp"

namespace posefuse::fit {
namespace {

void require(bool ok, const char* field, double value, const char* rule) {
  if (!ok || !std::isfinite(value))
    throw_invalid(std::string("fit_options.") + field, std::to_string(value) + " " + rule);
}

}  // namespace

void validate(const FitOptions& o) {
  require(o.num_samples > 0, "num_samples", o.num_samples, "must be positive");
  require(o.sigma_p_m > 0, "sigma_p_m", o.sigma_p_m, "must be positive");
  require(o.sigma_n > 0, "sigma_n", o.sigma_n, "must be positive");
  require(o.lambda_bg >= 0, "lambda_bg", o.lambda_bg, "must not be negative");
  require(o.lambda_bg_joint >= 0, "lambda_bg_joint", o.lambda_bg_joint, "must not be negative");
  require(o.lambda_float >= 0, "lambda_float", o.lambda_float, "must not be negative");
  require(o.lambda_limit >= 0, "lambda_limit", o.lambda_limit, "must not be negative");
  require(o.lambda_imu >= 0, "lambda_imu", o.lambda_imu, "must not be negative");
  require(o.max_bg_points >= 0, "max_bg_points", o.max_bg_points, "must not be negative");
  require(o.bg_contour_max_cos > 0 && o.bg_contour_max_cos <= 1, "bg_contour_max_cos", o.bg_contour_max_cos,
          "must be in (0, 1]");
  require(o.silhouette_edge_px >= 0, "silhouette_edge_px", o.silhouette_edge_px, "must not be negative");
  require(o.max_iterations >= 0, "max_iterations", o.max_iterations, "must not be negative");
  require(o.initial_damping > 0, "initial_damping", o.initial_damping, "must be positive");
  require(o.damping_increase > 1, "damping_increase", o.damping_increase, "must be above 1");
  require(o.damping_decrease > 0 && o.damping_decrease <= 1, "damping_decrease", o.damping_decrease,
          "must be in (0, 1]");
  require(o.max_damping > o.initial_damping, "max_damping", o.max_damping, "must exceed initial_damping");
  require(o.min_relative_decrease >= 0, "min_relative_decrease", o.min_relative_decrease, "must not be negative");
  require(o.min_joint_step_m >= 0, "min_joint_step_m", o.min_joint_step_m, "must not be negative");
  require(o.limit_projection_margin_rad >= 0, "limit_projection_margin_rad", o.limit_projection_margin_rad,
          "must not be negative");
  require(o.joint_step_stop_max_damping > 0, "joint_step_stop_max_damping", o.joint_step_stop_max_damping,
          "must be positive");
  require(o.freeze_contour_after >= 0, "freeze_contour_after", o.freeze_contour_after, "must not be negative");
  require(o.num_candidate_sets > 0, "num_candidate_sets", o.num_candidate_sets, "must be positive");
  require(o.candidates_per_set >= 0, "candidates_per_set", o.candidates_per_set, "must not be negative");
  require(o.limb_candidate_density >= 1, "limb_candidate_density", o.limb_candidate_density, "must be at least 1");
  require(o.max_climb_steps >= 0, "max_climb_steps", o.max_climb_steps, "must not be negative");
}

}  // namespace posefuse::fit
