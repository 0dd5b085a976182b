#pragma once
// A session's joint angles over time, kept for its repetitions: the series of one named angle,
// or of the arm and trunk angles exercises move (to pick the one that moves most), with
// undefined and held values as gaps. One code path for the server's measures stage and the
// simulator's ground truth, so both count repetitions alike.
#include <optional>
#include <vector>

#include "measures/joint_angles.hpp"
#include "measures/repetitions.hpp"

namespace posefuse::measures {

struct SessionRepetitions {
  Angle angle = Angle::kRightElevation;
  bool detected = false;  // chosen as the candidate that moves most (dominant_series)
  RepetitionSummary summary;
};

class AngleSeries {
 public:
  // `angle`: the one to segment; none: choose among the arm and trunk candidates (elevation,
  // elbow flexion and pronation of each arm, the thorax's flexion, lateral tilt and axial rotation).
  explicit AngleSeries(std::optional<Angle> angle = std::nullopt);

  // Frames in strictly increasing t_s; a frame not after the last is ignored (returns false).
  bool add(double t_s, const JointAngles& angles);
  std::size_t frames() const { return t_s_.size(); }
  // The memory the series take (session::Stage::held_bytes).
  std::size_t held_bytes() const;

  // None when no frame was added or no candidate was ever defined. The candidate is chosen by
  // dominant_series with the candidates' confidences and `options.min_amplitude_deg`. Throws as
  // segment_repetitions for bad options.
  std::optional<SessionRepetitions> repetitions(const RepetitionOptions& options) const;

 private:
  std::optional<Angle> named_;
  std::vector<Angle> candidates_;
  std::vector<double> t_s_;
  std::vector<std::vector<double>> series_deg_;  // per candidate; NaN where undefined or held
  std::vector<std::vector<float>> confidence_;   // per candidate; 0 where undefined or held
};

}  // namespace posefuse::measures
