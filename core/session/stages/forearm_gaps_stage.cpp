#include "session/stages/forearm_gaps_stage.hpp"

#include <algorithm>
#include <cmath>

#include "body/smpl_model.hpp"
#include "common/held_bytes.hpp"

namespace posefuse::session {

std::string_view ForearmGapsStage::description() const {
  return "IMU position per camera frame in occlusion gaps (live estimate) and each gap's trajectory once it ends "
         "(paper 1 and smoother), anchored to the body fit's elbows";
}

void ForearmGapsStage::start(const v1::SessionHeader& /*header*/, StageOutput& /*out*/) {
  arms_.clear();
  early_elbows_.clear();
}

void ForearmGapsStage::on_value(const StageValue& value, StageOutput& out) {
  if (const auto* start = std::get_if<ArmTrackStart>(&value)) start_arm(*start, out);
  if (const auto* track = std::get_if<ArmTrack>(&value)) add_track(*track, out);
  if (const auto* fitted = std::get_if<FittedFrame>(&value)) add_fit(*fitted, out);
}

void ForearmGapsStage::start_arm(const ArmTrackStart& start, StageOutput& /*out*/) {
  Arm arm{start.device_id, start.arm, nullptr};
  std::vector<forearm::FitElbow> early = std::move(early_elbows_[start.arm]);
  early_elbows_.erase(start.arm);
  if (start.tracked) {
    arm.tracker = std::make_unique<forearm::GapTracker>(start.device_id, start.model, start.has_model, start.K_from_W,
                                                        start.smoother);
    if (start.fit_anchor) {
      arm.tracker->use_fit_anchor(*start.fit_anchor);
      for (const forearm::FitElbow& elbow : early) arm.tracker->add_fit_elbow(elbow);
    }
  }
  arms_.push_back(std::move(arm));
}

void ForearmGapsStage::add_track(const ArmTrack& track, StageOutput& out) {
  const auto arm =
      std::find_if(arms_.begin(), arms_.end(), [&](const Arm& a) { return a.device_id == track.device_id; });
  if (arm == arms_.end() || !arm->tracker) return;
  arm->tracker->add_samples(track.samples);
  if (!track.frames.empty()) {
    ArmFrameEstimates estimates{arm->device_id, arm->arm, {}};
    for (const forearm::TrackedArmFrame& frame : track.frames)
      estimates.frames.push_back(arm->tracker->add_frame(frame));
    out.hand_on(std::move(estimates));
  }
  hand_on(*arm, arm->tracker->recover_ready(false), out);
}

void ForearmGapsStage::add_fit(const FittedFrame& fitted, StageOutput& out) {
  const FrameEstimate& frame = fitted.estimate;
  if (frame.smpl_joints.size() != static_cast<std::size_t>(body::kNumJoints)) return;
  for (const v1::Arm side : {v1::LEFT, v1::RIGHT}) {
    const forearm::FitElbow elbow{
        frame.t_us, frame.smpl_joints[side == v1::LEFT ? body::kLeftElbow : body::kRightElbow].p_K, frame.fit_energy};
    bool started = false;
    for (Arm& arm : arms_) {
      if (arm.arm != side) continue;
      started = true;
      if (!arm.tracker) continue;
      arm.tracker->add_fit_elbow(elbow);
      hand_on(arm, arm.tracker->recover_ready(false), out);  // a gap that waited for this frame
    }
    if (started) continue;
    std::vector<forearm::FitElbow>& early = early_elbows_[side];
    early.push_back(elbow);
    const auto keep_us = static_cast<std::int64_t>(std::llround(kEarlyElbowS * 1e6));
    const auto first_kept = std::find_if(early.begin(), early.end(),
                                         [&](const forearm::FitElbow& e) { return e.t_us >= elbow.t_us - keep_us; });
    early.erase(early.begin(), first_kept);
  }
}

void ForearmGapsStage::hand_on(Arm& arm, std::vector<forearm::RecoveredGapSegment>&& segments, StageOutput& out) {
  for (forearm::RecoveredGapSegment& segment : segments) {
    out.hand_on(RecoveredSegment{arm.device_id, arm.arm, std::move(segment)});
  }
  for (const forearm::ForearmWarning& w : arm.tracker->take_warnings()) out.warn(w.code, w.field, w.message);
}

std::size_t ForearmGapsStage::held_bytes() const {
  std::size_t held = 0;
  for (const Arm& arm : arms_) held += arm.tracker ? arm.tracker->held_bytes() : 0;
  for (const auto& [arm, elbows] : early_elbows_) held += posefuse::held_bytes(elbows);
  return held;
}

void ForearmGapsStage::finish(StageOutput& out) {
  for (Arm& arm : arms_) {
    if (!arm.tracker) continue;
    arm.tracker->fit_finished();  // the fit, before this stage, has finished
    hand_on(arm, arm.tracker->finish(), out);
  }
}

}  // namespace posefuse::session
