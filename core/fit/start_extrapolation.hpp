#pragma once
// Constant-velocity start for the previous-frame fit (ours, issue 7; paper 2 II-G starts from the
// previous frame's pose itself). With the last two fitted poses theta_1 (at t_1) and theta_2 (at
// t_2 < t_1), the start for a frame at t is theta_1 + (t - t_1) / (t_1 - t_2) * (theta_1 - theta_2),
// DOF by DOF (theta maps linearly onto SMPL's rotation vectors, so for the small changes between
// frames this is a constant angular and linear velocity). The rule falls back to theta_1 (nullopt)
// where a velocity is not to be trusted: a frame gap far longer than the last one, or a step
// between the two poses that is a jump rather than motion (a skeleton-start win, lost tracking).
#include <Eigen/Core>
#include <cstdint>
#include <optional>

#include "body/pose_parameters.hpp"

namespace posefuse::fit {

struct StartExtrapolationOptions {
  // Share of the velocity extrapolated (1: constant velocity; 0: off, the previous pose).
  double velocity_gain = 1.0;
  // The extrapolated change of one DOF above these is taken as a jump: no extrapolation.
  double max_rotation_rad = 0.35;  // 20 deg per frame: far beyond an arm's swing between frames
  double max_translation_m = 0.10;
  // No extrapolation when the frame comes more than this many times the last gap after theta_1.
  double max_gap_ratio = 1.5;
};

// Throws posefuse::Error naming "start_extrapolation.<field>" for a negative or non-finite value.
void validate(const StartExtrapolationOptions& options);

struct FittedPose {
  Eigen::VectorXd theta;
  std::int64_t t_us = 0;
};

// The start for a frame at `t_us`, or nullopt: start from `last` itself. Throws posefuse::Error
// ("theta") when the two poses do not have the layout's size.
std::optional<Eigen::VectorXd> extrapolate_start(const body::PoseLayout& layout, const FittedPose& before_last,
                                                 const FittedPose& last, std::int64_t t_us,
                                                 const StartExtrapolationOptions& options = {});

}  // namespace posefuse::fit
