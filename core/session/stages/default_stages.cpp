#include "session/stages/default_stages.hpp"

#include "session/stages/body_fit_stage.hpp"
#include "session/stages/forearm_gaps_stage.hpp"
#include "session/stages/forearm_stage.hpp"
#include "session/stages/frame_merge_stage.hpp"
#include "session/stages/imu_orientation_stage.hpp"
#include "session/stages/measures_stage.hpp"

namespace posefuse::session {

std::vector<std::unique_ptr<Stage>> make_default_stages() {
  std::vector<std::unique_ptr<Stage>> stages;
  stages.push_back(std::make_unique<ImuOrientationStage>());
  stages.push_back(std::make_unique<ForearmStage>());  // needs the IMU orientations first
  // Needs the forearm orientations; off unless the header sets fit.enabled (speed, see its option).
  stages.push_back(std::make_unique<BodyFitStage>());
  // The gaps see the fit's elbows as an earlier result; the merge sees every per-frame estimate.
  stages.push_back(std::make_unique<ForearmGapsStage>());
  stages.push_back(std::make_unique<FrameMergeStage>());
  // Joint angles and repetitions from the merged frames' fitted joints and forearm orientations.
  stages.push_back(std::make_unique<MeasuresStage>());
  return stages;
}

}  // namespace posefuse::session
