#include "session/stages/frame_merge_stage.hpp"

#include "session/text_fields.hpp"

namespace posefuse::session {

std::string_view FrameMergeStage::description() const {
  return "one result per camera frame: the body fit's joints, the forearm stage's orientation, the best IMU "
         "position (strap, recovered gap, live estimate), each with its source and confidence";
}

void FrameMergeStage::start(const v1::SessionHeader& /*header*/, StageOutput& /*out*/) { merger_ = FrameMerger(); }

void FrameMergeStage::on_value(const StageValue& value, StageOutput& /*out*/) {
  std::visit(
      [&](const auto& v) {
        using T = std::decay_t<decltype(v)>;
        if constexpr (std::is_same_v<T, FittedFrame> || std::is_same_v<T, ArmFrameEstimates> ||
                      std::is_same_v<T, RecoveredSegment> || std::is_same_v<T, FramesDone>) {
          merger_.add(v);
        }
      },
      value);
}

void FrameMergeStage::on_camera_frame(const CameraFrame& /*frame*/, StageOutput& out) {
  for (FrameEstimate& frame : merger_.take_complete()) out.hand_on(std::move(frame));
}

void FrameMergeStage::finish(StageOutput& out) {
  for (FrameEstimate& frame : merger_.finish()) out.hand_on(std::move(frame));
  if (merger_.incomplete_frames() > 0) {
    out.warn("MERGE_FRAME_INCOMPLETE", "frames",
             std::to_string(merger_.incomplete_frames()) + " frames sent without every stage's estimate: held " +
                 format_double(kMaxHoldS) + " s of camera time, the most a frame waits");
  }
  if (merger_.late_parts() > 0) {
    out.warn("MERGE_LATE_ESTIMATE", "frames",
             std::to_string(merger_.late_parts()) +
                 " per-frame estimates came after their frame had been sent "
                 "(not in the FrameResults)");
  }
}

}  // namespace posefuse::session
