#include "session/frame_merge.hpp"

#include <algorithm>
#include <cmath>

#include "common/held_bytes.hpp"
#include "forearm/orientation_uncertainty.hpp"

namespace posefuse::session {

namespace {

v1::Source position_source(forearm::PositionSource source) {
  switch (source) {
    case forearm::PositionSource::kVisual: return v1::VISUAL;
    case forearm::PositionSource::kPredicted: return v1::PREDICTED;
    case forearm::PositionSource::kNone: break;
  }
  return v1::SOURCE_UNSPECIFIED;
}

// The segment's IMU position at t_us (strictly inside it), linear between its samples.
std::optional<geometry::Vec3> position_inside(const forearm::RecoveredGapSegment& segment, std::int64_t t_us) {
  if (t_us <= segment.t_start_us || t_us >= segment.t_end_us) return std::nullopt;
  const auto& s = segment.samples;
  const auto after = std::lower_bound(s.begin(), s.end(), t_us,
                                      [](const forearm::RecoveredGapSample& a, std::int64_t t) { return a.t_us < t; });
  if (after == s.end() || after == s.begin()) return std::nullopt;
  const auto before = std::prev(after);
  if (after->t_us == t_us) return after->imu_K;
  const double f = static_cast<double>(t_us - before->t_us) / static_cast<double>(after->t_us - before->t_us);
  return ((1.0 - f) * before->imu_K + f * after->imu_K).eval();
}

}  // namespace

FrameEstimate merge_frame(const FrameParts& parts) {
  FrameEstimate merged;
  merged.t_us = parts.t_us;
  if (parts.fit) {
    const FrameEstimate& fit = parts.fit->estimate;
    merged.smpl_joints = fit.smpl_joints;
    merged.camera_joints = fit.camera_joints;
    merged.smpl_rotations = fit.smpl_rotations;
    merged.fit_energy = fit.fit_energy;
    if (parts.fit->lost) {
      for (auto* joints : {&merged.smpl_joints, &merged.camera_joints}) {
        for (JointEstimate& j : *joints) j.confidence = std::min(j.confidence, kLostFitConfidence);
      }
    }
  }
  for (const FrameParts::Arm& arm : parts.arms) {
    const forearm::ArmFrameEstimate& e = arm.estimate;
    merged.forearms.push_back(
        {arm.arm, e.K_from_F, e.pronation_rad, v1::FUSED, forearm::confidence_from_rms_rad(e.orientation_rms_rad)});
    const auto recovered = std::find_if(parts.recovered.begin(), parts.recovered.end(),
                                        [&](const FrameParts::Recovered& r) { return r.device_id == arm.device_id; });
    if (e.source == forearm::PositionSource::kVisual) {
      merged.imu_positions.push_back({arm.device_id, e.imu_K, v1::VISUAL});
    } else if (recovered != parts.recovered.end()) {
      merged.imu_positions.push_back({arm.device_id, recovered->imu_K, v1::RECOVERED});
    } else if (e.source != forearm::PositionSource::kNone) {
      merged.imu_positions.push_back({arm.device_id, e.imu_K, position_source(e.source)});
    }
  }
  if (parts.fit) {
    for (ForearmEstimate forearm : parts.fit->estimate.forearms) {
      const bool tracked = std::any_of(merged.forearms.begin(), merged.forearms.end(),
                                       [&](const ForearmEstimate& f) { return f.arm == forearm.arm; });
      if (tracked) continue;
      if (parts.fit->lost) forearm.confidence = std::min(forearm.confidence, kLostFitConfidence);
      merged.forearms.push_back(forearm);
    }
  }
  return merged;
}

FrameEstimate merge_fit_only(const FittedFrame& fit) {
  FrameParts parts;
  parts.t_us = fit.estimate.t_us;
  parts.fit = fit;
  return merge_frame(parts);
}

namespace {

std::size_t estimate_bytes(const FrameEstimate& e) {
  return held_bytes(e.smpl_joints) + held_bytes(e.camera_joints) + held_bytes(e.smpl_rotations) +
         held_bytes(e.forearms) + held_bytes(e.imu_positions);
}

// One held frame's memory: its map node and what its parts hold.
std::size_t parts_bytes(const FrameParts& parts) {
  return sizeof(std::pair<const std::int64_t, FrameParts>) + kMapNodeOverheadBytes +
         (parts.fit ? estimate_bytes(parts.fit->estimate) : 0) + held_bytes(parts.arms) + held_bytes(parts.recovered);
}

}  // namespace

FrameParts* FrameMerger::parts_at(std::int64_t t_us) {
  if (last_sent_us_ && t_us <= *last_sent_us_) {
    ++late_parts_;
    return nullptr;
  }
  const auto [it, created] = held_.try_emplace(t_us);
  FrameParts& parts = it->second;
  parts.t_us = t_us;
  if (created) held_bytes_ += parts_bytes(parts);
  if (!newest_us_ || t_us > *newest_us_) newest_us_ = t_us;
  return &parts;
}

template <class Change>
void FrameMerger::change(FrameParts& parts, Change&& change) {
  held_bytes_ -= parts_bytes(parts);
  change(parts);
  held_bytes_ += parts_bytes(parts);
}

void FrameMerger::add(const FittedFrame& frame) {
  if (FrameParts* parts = parts_at(frame.estimate.t_us)) change(*parts, [&](FrameParts& p) { p.fit = frame; });
}

void FrameMerger::add(const ArmFrameEstimates& estimates) {
  for (const forearm::ArmFrameEstimate& e : estimates.frames) {
    if (FrameParts* parts = parts_at(e.t_us)) {
      change(*parts, [&](FrameParts& p) { p.arms.push_back({estimates.device_id, estimates.arm, e}); });
    }
  }
}

void FrameMerger::add(const RecoveredSegment& segment) {
  if (segment.segment.method != forearm::RecoveryMethod::kSmoother) return;
  for (auto it = held_.upper_bound(segment.segment.t_start_us);
       it != held_.end() && it->first < segment.segment.t_end_us; ++it) {
    if (const auto p = position_inside(segment.segment, it->first))
      change(it->second, [&](FrameParts& parts) { parts.recovered.push_back({segment.device_id, *p}); });
  }
}

void FrameMerger::add(const FramesDone& done) {
  auto [it, inserted] = done_up_to_us_.try_emplace(done.source, done.up_to_t_us);
  std::int64_t& up_to = it->second;
  up_to = std::max(up_to, done.up_to_t_us);
}

std::vector<FrameEstimate> FrameMerger::take_complete() {
  std::vector<FrameEstimate> out;
  std::int64_t complete_up_to = INT64_MAX;
  for (const auto& [source, up_to] : done_up_to_us_) complete_up_to = std::min(complete_up_to, up_to);
  if (done_up_to_us_.empty()) complete_up_to = INT64_MIN;
  const auto max_hold_us = static_cast<std::int64_t>(std::llround(kMaxHoldS * 1e6));
  while (!held_.empty()) {
    const auto oldest = held_.begin();
    const bool complete = oldest->first <= complete_up_to;
    const bool held_too_long = newest_us_ && *newest_us_ - oldest->first > max_hold_us;
    if (!complete && !held_too_long) break;
    if (!complete) ++incomplete_frames_;
    out.push_back(merge_frame(oldest->second));
    last_sent_us_ = oldest->first;
    held_bytes_ -= parts_bytes(oldest->second);
    held_.erase(oldest);
  }
  return out;
}

std::vector<FrameEstimate> FrameMerger::finish() {
  std::vector<FrameEstimate> out;
  for (const auto& [t_us, parts] : held_) {
    out.push_back(merge_frame(parts));
    last_sent_us_ = t_us;
  }
  held_.clear();
  held_bytes_ = 0;
  return out;
}

}  // namespace posefuse::session
