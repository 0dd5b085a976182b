#pragma once
// The frame merge: one FrameEstimate per camera frame from what the stages before it estimated
// for that frame, by one rule (docs/architecture.md, "Pipeline stages"):
//  - body joints (24 SMPL, 25 camera-compatible) and the fit energy: the body fit's. Where the
//    fit lost tracking (energy above fit.lost_energy) they stay, with their confidence capped at
//    kLostFitConfidence;
//  - each arm's forearm orientation and pronation: the forearm stage's (paper 1 eq. 11, from the
//    IMU) wherever it tracks the arm; the fit's copy, the same IMU orientation turned onto the
//    fitted forearm, was 1-4.6 deg worse on the body render's protocol (docs/forearm.md). The
//    fit's only for an arm the forearm stage does not track. The forearm stage's confidence is
//    its predicted error's (forearm/orientation_uncertainty.hpp);
//  - each arm IMU's position: VISUAL (the strap seen, eq. 10) where the forearm stage has it,
//    else RECOVERED where a gap's smoother trajectory covering the frame has arrived, else the
//    live PREDICTED estimate, else none.
// FrameMerger holds a frame's parts until every stage that contributes per-frame values has
// said it has handed on all of them up to the frame's time (FramesDone), and at most
// kMaxHoldS of camera time behind the newest frame.
#include <cstdint>
#include <map>
#include <optional>
#include <string>
#include <vector>

#include "session/stage_values.hpp"

namespace posefuse::session {

// A lost fit's joints say nothing one can act on: on the joint-angle bench's tuning sessions the
// angles of frames fitted above fit.lost_energy reach a 99 % error bound of 114 degrees,
// confidence 2^-(114/15)^2 < 1e-17 (docs/benchmarks.md, "Fit energy and confidence"). 0 also
// keeps them apart from an untrusted fit's (fit::untrusted_fit_confidence).
inline constexpr double kLostFitConfidence = 0.0;
// Beyond the longest wait an earlier stage may take (fit.imu_wait_s <= 60 s).
inline constexpr double kMaxHoldS = 70.0;

// What the stages estimated for one camera frame.
struct FrameParts {
  std::int64_t t_us = 0;
  std::optional<FittedFrame> fit;
  struct Arm {
    std::string device_id;
    v1::Arm arm = v1::ARM_UNSPECIFIED;
    forearm::ArmFrameEstimate estimate;
  };
  std::vector<Arm> arms;
  struct Recovered {
    std::string device_id;
    geometry::Vec3 imu_K = geometry::Vec3::Zero();
  };
  std::vector<Recovered> recovered;  // from a SMOOTHER segment covering the frame
};

FrameEstimate merge_frame(const FrameParts& parts);
// The frame as the client receives it when the fit is all that estimated it (for benches and
// tests of the fit stage alone).
FrameEstimate merge_fit_only(const FittedFrame& fit);

class FrameMerger {
 public:
  void add(const FittedFrame& frame);
  void add(const ArmFrameEstimates& estimates);
  void add(const RecoveredSegment& segment);  // only SMOOTHER segments are used
  void add(const FramesDone& done);
  // The frames every contributing stage has passed, merged, in time order; and the frames held
  // longer than kMaxHoldS (incomplete: counted in incomplete_frames()).
  std::vector<FrameEstimate> take_complete();
  // End of session: every frame held, merged.
  std::vector<FrameEstimate> finish();

  std::size_t frames_held() const { return held_.size(); }
  std::size_t held_bytes() const { return held_bytes_; }  // the frames held (Stage::held_bytes)
  std::uint64_t incomplete_frames() const { return incomplete_frames_; }
  // Parts for a frame already sent (dropped: the client has that frame's result).
  std::uint64_t late_parts() const { return late_parts_; }

 private:
  // The frame's parts; none for a frame already sent (counted as late).
  FrameParts* parts_at(std::int64_t t_us);
  // Applies `change` to a held frame, keeping held_bytes_.
  template <class Change>
  void change(FrameParts& parts, Change&& change);
  std::map<std::int64_t, FrameParts> held_;
  std::size_t held_bytes_ = 0;
  std::map<FrameSource, std::int64_t> done_up_to_us_;
  std::optional<std::int64_t> newest_us_;
  std::optional<std::int64_t> last_sent_us_;
  std::uint64_t incomplete_frames_ = 0;
  std::uint64_t late_parts_ = 0;
};

}  // namespace posefuse::session
