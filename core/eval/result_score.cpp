#include "eval/result_score.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>
#include <optional>
#include <sstream>

#include "common/error.hpp"
#include "eval/orientation_error.hpp"
#include "forearm/orientation_uncertainty.hpp"
#include "measures/joint_angles.hpp"
#include "measures/repetitions.hpp"
#include "session/result_files.hpp"
#include "session/text_fields.hpp"

namespace posefuse::eval {

namespace {

namespace fs = std::filesystem;
namespace layout = session::result_layout;
constexpr double kDegPerRad = 180.0 / 3.14159265358979323846;
constexpr double kConfidentBoundDeg = forearm::kConfidentErrorBoundRad * kDegPerRad;

// Index of the element of sorted `times` nearest to t, if within the tolerance.
std::optional<std::size_t> nearest(const std::vector<std::int64_t>& times, std::int64_t t, std::int64_t tolerance_us) {
  const auto it = std::lower_bound(times.begin(), times.end(), t);
  std::optional<std::size_t> best;
  std::int64_t best_gap = tolerance_us;
  for (auto c = it == times.begin() ? it : it - 1; c != times.end() && c <= it; ++c) {
    const std::int64_t gap = std::abs(*c - t);
    if (gap <= best_gap) {
      best_gap = gap;
      best = static_cast<std::size_t>(c - times.begin());
    }
  }
  return best;
}

std::string span(const std::vector<std::int64_t>& times) {
  if (times.empty()) return "none";
  return std::to_string(times.front()) + ".." + std::to_string(times.back()) + " us";
}

// No result row of `stream` had a truth row within the tolerance.
[[noreturn]] void throw_unmatched(const std::string& stream, const std::vector<std::int64_t>& result_times,
                                  const std::vector<std::int64_t>& truth_times, const ScoreOptions& options) {
  throw_invalid(stream, "no t_us within " + std::to_string(options.tolerance_us) + " us of the truth's: results " +
                            span(result_times) + ", truth " + span(truth_times));
}

void require_truth(const session::ResultDirectory& truth, const std::string& file) {
  if (!truth.has(file)) {
    throw Error(ErrorCode::kNotFound, (truth.directory / file).string(),
                "missing in the truth directory, but the results have it");
  }
}

// A row's confidence and predicted error, where its file has them.
std::optional<double> confidence_of(const session::TimedOrientation& r) { return r.confidence; }
std::optional<double> confidence_of(const session::ForearmRow& r) { return r.confidence; }
std::optional<double> uncertainty_of(const session::TimedOrientation& r) { return r.uncertainty_rad; }
std::optional<double> uncertainty_of(const session::ForearmRow&) { return std::nullopt; }

template <typename Row>
void score_confidence(const Row& r, double error_deg, std::int64_t first_t_us, AngleScore& score,
                      std::vector<double>& confident_errors) {
  if (const std::optional<double> confidence = confidence_of(r)) {
    ++score.with_confidence;
    if (*confidence >= forearm::kConfidentAt) {
      confident_errors.push_back(error_deg);
      score.confident_beyond_15_deg += error_deg > kConfidentBoundDeg;
      if (!score.first_confident_s) score.first_confident_s = 1e-6 * static_cast<double>(r.t_us - first_t_us);
    }
  }
  if (const std::optional<double> u = uncertainty_of(r)) {
    ++score.with_uncertainty;
    score.within_predicted_bound += error_deg <= forearm::kBound99OverRms * *u * kDegPerRad;
  }
}

// Scores one orientation stream: result rows against truth rows matched in time.
template <typename Row, typename GetQuat>
AngleScore score_angles(const std::string& stream, const std::string& key, const std::vector<Row>& result,
                        const std::vector<Row>& truth, GetQuat quat_of, bool heading, const ScoreOptions& options) {
  std::vector<std::int64_t> truth_times, result_times;
  for (const Row& r : truth) truth_times.push_back(r.t_us);
  std::vector<double> errors, heading_errors, confident_errors;
  AngleScore score;
  score.stream = stream;
  score.key = key;
  for (const Row& r : result) {
    result_times.push_back(r.t_us);
    const auto i = nearest(truth_times, r.t_us, options.tolerance_us);
    if (!i) {
      ++score.unmatched;
      continue;
    }
    errors.push_back(paper_orientation_error_deg(quat_of(r), quat_of(truth[*i])));
    if (heading) heading_errors.push_back(orientation_error(quat_of(r), quat_of(truth[*i])).heading_rad * kDegPerRad);
    score_confidence(r, errors.back(), result.front().t_us, score, confident_errors);
  }
  if (!result.empty() && errors.empty()) throw_unmatched(stream + " (" + key + ")", result_times, truth_times, options);
  score.deg = summarize_errors(errors);
  score.heading_deg = summarize_errors(heading_errors);
  score.confident_deg = summarize_errors(confident_errors);
  return score;
}

void score_orientation_folders(const session::ResultDirectory& result, const session::ResultDirectory& truth,
                               const ScoreOptions& options, ScoreReport& report) {
  const auto quat = [](const session::TimedOrientation& r) { return r.q; };
  for (const bool forearm : {false, true}) {
    const char* folder = forearm ? layout::kForearmOrientationDir : layout::kImuOrientationDir;
    const auto& results = forearm ? result.forearm_orientations : result.imu_orientations;
    const auto& truths = forearm ? truth.forearm_orientations : truth.imu_orientations;
    for (const auto& [device, rows] : results) {
      const std::string file = std::string(folder) + "/" + device + ".csv";
      require_truth(truth, file);
      report.orientations.push_back(score_angles(file, device, rows, truths.at(device), quat, !forearm, options));
    }
    for (const auto& [device, rows] : truths) {
      if (!results.count(device))
        report.notes.push_back(std::string(folder) + "/" + device + ".csv: not in the results");
    }
  }
  // The offline solution has the live folder's truth (gt/ has one solution: the truth).
  for (const auto& [device, rows] : result.offline_forearm_orientations) {
    const std::string file = std::string(layout::kForearmOrientationOfflineDir) + "/" + device + ".csv";
    const std::string truth_file = std::string(layout::kForearmOrientationDir) + "/" + device + ".csv";
    require_truth(truth, truth_file);
    report.orientations.push_back(
        score_angles(file, device, rows, truth.forearm_orientations.at(device), quat, false, options));
  }
}

void score_forearms(const session::ResultDirectory& result, const session::ResultDirectory& truth,
                    const ScoreOptions& options, ScoreReport& report) {
  if (result.forearms.empty()) return;
  require_truth(truth, layout::kForearmsCsv);
  for (const v1::Arm arm : {v1::LEFT, v1::RIGHT}) {
    std::vector<session::ForearmRow> mine, theirs;
    for (const auto& r : result.forearms) {
      if (r.arm == arm && r.source != v1::SOURCE_UNSPECIFIED) mine.push_back(r);
    }
    for (const auto& r : truth.forearms) {
      if (r.arm == arm) theirs.push_back(r);
    }
    if (mine.empty()) continue;
    report.orientations.push_back(score_angles(
        layout::kForearmsCsv, v1::Arm_Name(arm), mine, theirs, [](const session::ForearmRow& r) { return r.K_from_F; },
        false, options));
  }
}

// The truth's position of each device, by frame time.
struct PositionTrack {
  std::vector<std::int64_t> t_us;
  std::vector<geometry::Vec3> p_K;
};
std::map<std::string, PositionTrack> tracks_by_device(const std::vector<session::ImuPositionRow>& rows) {
  std::map<std::string, PositionTrack> tracks;
  for (const auto& r : rows) {
    tracks[r.device_id].t_us.push_back(r.t_us);
    tracks[r.device_id].p_K.push_back(r.p_K);
  }
  return tracks;
}

// Arm of each arm IMU: the truth's calibration report names it (the results' as a fallback).
std::map<std::string, v1::Arm> arms_by_device(const session::ResultDirectory& result,
                                              const session::ResultDirectory& truth) {
  std::map<std::string, v1::Arm> arms;
  for (const auto* dir : {&result, &truth}) {
    if (!dir->calibration) continue;
    for (const v1::ForearmModel& f : dir->calibration->forearms()) {
      if (!f.device_id().empty()) arms[f.device_id()] = f.arm();
    }
  }
  return arms;
}

void score_recovered(const session::ResultDirectory& result, const std::map<std::string, PositionTrack>& truth,
                     ScoreReport& report) {
  // Errors per device and method, over the truth frames inside each segment.
  std::map<std::pair<std::string, std::string>, std::vector<double>> errors;
  std::size_t begin = 0;
  const auto& rows = result.recovered;
  while (begin < rows.size()) {
    std::size_t end = begin + 1;
    while (end < rows.size() && rows[end].device_id == rows[begin].device_id &&
           rows[end].method == rows[begin].method && rows[end].t_start_us == rows[begin].t_start_us &&
           rows[end].t_end_us == rows[begin].t_end_us) {
      ++end;
    }
    const std::string method = "recovered " + v1::RecoveredSegment::Method_Name(rows[begin].method);
    auto& out = errors[{rows[begin].device_id, method}];
    const auto track = truth.find(rows[begin].device_id);
    if (track != truth.end()) {
      for (std::size_t f = 0; f < track->second.t_us.size(); ++f) {
        const std::int64_t t = track->second.t_us[f];
        if (t < rows[begin].t_us || t > rows[end - 1].t_us) continue;
        std::size_t k = begin;
        while (k + 1 < end && rows[k + 1].t_us < t) ++k;
        const auto& a = rows[k];
        const auto& b = rows[std::min(k + 1, end - 1)];
        const double span_us = static_cast<double>(b.t_us - a.t_us);
        const double u = span_us > 0.0 ? static_cast<double>(t - a.t_us) / span_us : 0.0;
        out.push_back((a.imu_K + u * (b.imu_K - a.imu_K) - track->second.p_K[f]).norm());
      }
    }
    begin = end;
  }
  for (const auto& [key, e] : errors) report.positions.push_back({key.first, key.second, summarize_errors(e), 0});
}

void score_positions(const session::ResultDirectory& result, const session::ResultDirectory& truth,
                     const std::vector<OcclusionRow>& occlusion, const ScoreOptions& options, ScoreReport& report) {
  if (result.imu_positions.empty() && result.recovered.empty()) return;
  require_truth(truth, layout::kImuPositionsCsv);
  const auto truth_tracks = tracks_by_device(truth.imu_positions);
  const auto arms = arms_by_device(result, truth);
  std::map<std::string, std::vector<const session::ImuPositionRow*>> by_device;
  for (const auto& r : result.imu_positions) by_device[r.device_id].push_back(&r);
  for (const auto& [device, rows] : by_device) {
    const auto track = truth_tracks.find(device);
    std::vector<std::int64_t> result_times;
    for (const auto* r : rows) result_times.push_back(r->t_us);
    if (track == truth_tracks.end())
      throw_unmatched(std::string(layout::kImuPositionsCsv) + " (" + device + ")", result_times, {}, options);
    std::vector<std::int64_t> occluded_times;
    const auto arm = arms.find(device);
    for (const auto& o : occlusion) {
      if (arm != arms.end() && o.arm == arm->second && o.occluded) occluded_times.push_back(o.t_us);
    }
    std::vector<double> errors;
    std::vector<bool> visual, predicted, occluded;
    std::size_t unmatched = 0;
    for (const auto* r : rows) {
      const auto i = nearest(track->second.t_us, r->t_us, options.tolerance_us);
      if (!i) {
        ++unmatched;
        continue;
      }
      errors.push_back((r->p_K - track->second.p_K[*i]).norm());
      visual.push_back(r->source == v1::VISUAL);
      predicted.push_back(r->source == v1::PREDICTED);
      occluded.push_back(nearest(occluded_times, track->second.t_us[*i], 0).has_value());
    }
    if (errors.empty())
      throw_unmatched(std::string(layout::kImuPositionsCsv) + " (" + device + ")", result_times, track->second.t_us,
                      options);
    report.positions.push_back({device, "all", summarize_errors(errors), unmatched});
    report.positions.push_back({device, "VISUAL", summarize_errors(errors, visual), 0});
    report.positions.push_back({device, "PREDICTED", summarize_errors(errors, predicted), 0});
    if (!occlusion.empty())
      report.positions.push_back({device, "occluded (gt)", summarize_errors(errors, occluded), 0});
  }
  score_recovered(result, truth_tracks, report);
}

// Joint groups by index: SMPL order (body/smpl_model.hpp) and Kinect v2 JointType order.
struct JointGroup {
  const char* name;
  std::vector<int> joints;
};
const std::vector<JointGroup>& smpl_groups() {
  static const std::vector<JointGroup> groups = {{"torso+head", {0, 3, 6, 9, 12, 13, 14, 15}},
                                                 {"left arm", {16, 18, 20, 22}},
                                                 {"right arm", {17, 19, 21, 23}},
                                                 {"legs", {1, 2, 4, 5, 7, 8, 10, 11}}};
  return groups;
}
const std::vector<JointGroup>& camera_groups() {
  static const std::vector<JointGroup> groups = {{"torso+head", {0, 1, 2, 3, 20}},
                                                 {"left arm", {4, 5, 6, 7, 21, 22}},
                                                 {"right arm", {8, 9, 10, 11, 23, 24}},
                                                 {"legs", {12, 13, 14, 15, 16, 17, 18, 19}}};
  return groups;
}

void score_joints(const std::string& stream, const std::vector<session::JointRow>& result,
                  const std::vector<session::JointRow>& truth, const std::vector<JointGroup>& groups,
                  const ScoreOptions& options, ScoreReport& report) {
  // Truth per frame: frame times and, per frame, each joint's row.
  std::vector<std::int64_t> frame_times;
  std::vector<std::map<int, geometry::Vec3>> frames;
  for (const auto& r : truth) {
    if (frame_times.empty() || frame_times.back() != r.t_us) {
      frame_times.push_back(r.t_us);
      frames.emplace_back();
    }
    frames.back()[r.joint] = r.p_K;
  }
  std::map<int, std::vector<double>> errors;  // by joint
  std::size_t unmatched = 0;
  std::vector<std::int64_t> result_times;
  for (const auto& r : result) {
    if (r.source == v1::SOURCE_UNSPECIFIED) continue;  // not estimated: the value is meaningless
    result_times.push_back(r.t_us);
    const auto f = nearest(frame_times, r.t_us, options.tolerance_us);
    const auto joint = f ? frames[*f].find(r.joint) : std::map<int, geometry::Vec3>::const_iterator{};
    if (!f || joint == frames[*f].end()) {
      ++unmatched;
      continue;
    }
    errors[r.joint].push_back((r.p_K - joint->second).norm());
  }
  if (errors.empty()) throw_unmatched(stream, result_times, frame_times, options);
  for (const JointGroup& g : groups) {
    JointGroupScore s{stream, g.name, 0.0, 0.0, 0, 0};
    double sum = 0.0;
    for (const int j : g.joints) {
      for (const double e : errors[j]) {
        sum += e;
        s.max_m = std::max(s.max_m, e);
        ++s.count;
      }
    }
    if (s.count == 0) continue;
    s.mean_m = sum / static_cast<double>(s.count);
    report.joints.push_back(s);
  }
  if (unmatched > 0) report.notes.push_back(stream + ": " + std::to_string(unmatched) + " joint rows without truth");
}

void score_joint_angles(const session::ResultDirectory& result, const session::ResultDirectory& truth,
                        const ScoreOptions& options, ScoreReport& report) {
  std::vector<std::int64_t> truth_times;
  for (const auto& row : truth.joint_angles) truth_times.push_back(row.t_us);
  std::vector<std::int64_t> result_times;
  const auto count = static_cast<std::size_t>(measures::kAngleCount);
  std::vector<std::vector<double>> errors(count), confident_errors(count);
  std::vector<std::size_t> undefined(count, 0);
  std::size_t unmatched = 0;
  for (const auto& row : result.joint_angles) {
    result_times.push_back(row.t_us);
    const auto f = nearest(truth_times, row.t_us, options.tolerance_us);
    if (!f) {
      ++unmatched;
      continue;
    }
    const session::AngleRow& want = truth.joint_angles[*f];
    for (std::size_t a = 0; a < count; ++a) {
      // Truth with confidence 0 is a value of the gimbal lock (the held plane of elevation, the axial
      // rotation that depends on it): not a value to score.
      if (!want.deg[a] || want.confidence[a] <= 0.0) continue;
      if (!row.deg[a]) {
        ++undefined[a];
        continue;
      }
      errors[a].push_back(std::abs(std::remainder(*row.deg[a] - *want.deg[a], 360.0)));
      if (row.confidence[a] >= measures::kConfidentAt) confident_errors[a].push_back(errors[a].back());
    }
  }
  if (unmatched == result.joint_angles.size()) {
    throw_unmatched(layout::kJointAnglesCsv, result_times, truth_times, options);
  }
  for (std::size_t a = 0; a < count; ++a) {
    if (errors[a].empty() && undefined[a] == 0) continue;
    report.joint_angles.push_back({std::string(measures::angle_name(static_cast<measures::Angle>(a))),
                                   summarize_errors(errors[a]), summarize_errors(confident_errors[a]), undefined[a],
                                   unmatched});
  }
}

void score_repetitions(const session::ResultDirectory& result, const session::ResultDirectory& truth,
                       ScoreReport& report) {
  RepetitionScore score;
  std::vector<const session::RepetitionRow*> mine, theirs;
  for (const auto& r : result.repetitions) {
    score.result_angle = r.angle;
    if (r.counted) mine.push_back(&r);
  }
  for (const auto& r : truth.repetitions) {
    score.truth_angle = r.angle;
    if (r.counted) theirs.push_back(&r);
  }
  // Where the two picked different dominant angles (the two arms of a symmetric exercise), the
  // truth's repetitions of the result's angle are the fair comparison: segment the true series
  // of that angle with the default options.
  std::vector<session::RepetitionRow> resegmented;
  if (!score.result_angle.empty() && score.result_angle != score.truth_angle && !truth.joint_angles.empty()) {
    for (int a = 0; a < measures::kAngleCount; ++a) {
      if (measures::angle_name(static_cast<measures::Angle>(a)) != score.result_angle) continue;
      std::vector<double> t_s, deg;
      for (const session::AngleRow& row : truth.joint_angles) {
        t_s.push_back(static_cast<double>(row.t_us) * 1e-6);
        deg.push_back(row.deg[static_cast<std::size_t>(a)].value_or(std::numeric_limits<double>::quiet_NaN()));
      }
      for (const measures::Repetition& r : measures::segment_repetitions(t_s, deg).repetitions) {
        resegmented.push_back({score.result_angle, r.t_start_s, r.t_peak_s, r.t_end_s, r.min_deg, r.max_deg,
                               r.range_deg, r.peak_speed_deg_s, r.duration_s, !r.partial, r.confidence});
      }
      report.notes.push_back("repetitions: the truth's dominant angle is " + score.truth_angle +
                             "; scored against the truth's " + score.result_angle + " (default options)");
      score.truth_angle = score.result_angle;
      theirs.clear();
      for (const session::RepetitionRow& r : resegmented)
        if (r.counted) theirs.push_back(&r);
    }
  }
  score.result_count = mine.size();
  score.truth_count = theirs.size();
  std::vector<double> range_errors, confident_range_errors;
  for (const session::RepetitionRow* want : theirs) {
    const session::RepetitionRow* best = nullptr;
    double best_overlap = 0.0;
    for (const session::RepetitionRow* got : mine) {
      const double overlap = std::min(got->t_end_s, want->t_end_s) - std::max(got->t_start_s, want->t_start_s);
      if (overlap > best_overlap) {
        best_overlap = overlap;
        best = got;
      }
    }
    if (!best) continue;
    range_errors.push_back(std::abs(best->range_deg - want->range_deg));
    if (best->confidence >= measures::kConfidentAt) confident_range_errors.push_back(range_errors.back());
  }
  score.matched = range_errors.size();
  score.range_deg = summarize_errors(range_errors);
  score.confident_range_deg = summarize_errors(confident_range_errors);
  report.repetitions = score;
}

geometry::Quat quat_of(const v1::Quaternion& q) { return geometry::Quat(q.w(), q.x(), q.y(), q.z()); }
geometry::Vec3 vec_of(const v1::Vec3& v) { return {v.x(), v.y(), v.z()}; }

void score_calibration(const session::ResultDirectory& result, const session::ResultDirectory& truth,
                       ScoreReport& report) {
  if (!result.calibration) return;
  require_truth(truth, layout::kCalibrationJson);
  const v1::CalibrationReport& mine = *result.calibration;
  const v1::CalibrationReport& theirs = *truth.calibration;
  const auto add = [&](std::string name, std::string unit, double r, double t, double uncertainty = 0.0) {
    report.calibration.push_back({std::move(name), std::move(unit), r, t, r - t, uncertainty});
  };
  const auto add_angle = [&](std::string name, const v1::Quaternion& r, const v1::Quaternion& t) {
    report.calibration.push_back(
        {std::move(name), "deg", 0.0, 0.0, paper_orientation_error_deg(quat_of(r), quat_of(t))});
  };
  if (mine.has_k_from_w() && theirs.has_k_from_w()) add_angle("K_from_W", mine.k_from_w(), theirs.k_from_w());
  for (const v1::ForearmModel& f : mine.forearms()) {
    const auto t = std::find_if(theirs.forearms().begin(), theirs.forearms().end(),
                                [&](const v1::ForearmModel& g) { return g.arm() == f.arm(); });
    if (t == theirs.forearms().end()) {
      report.notes.push_back("calibration.json: no true forearm for arm " + v1::Arm_Name(f.arm()));
      continue;
    }
    const std::string arm = v1::Arm_Name(f.arm()) + " ";
    // A mounting from motion has no strap model: r, d_se, d_sw and d_ul are not estimated.
    if (f.mounting_source() != v1::ForearmModel::MOTION) {
      add(arm + "r", "m", f.r_m(), t->r_m());
      add(arm + "d_se", "m", f.d_se_m(), t->d_se_m());
      add(arm + "d_sw", "m", f.d_sw_m(), t->d_sw_m());
      add(arm + "d_ul", "m", f.d_ul_m(), t->d_ul_m(), f.d_ul_uncertainty_m());
    }
    add_angle(arm + "A_from_F", f.a_from_f(), t->a_from_f());
  }
  // 0 means none measured (no audio) or, in gt/, no buzzer.
  if (mine.buzzer_tone_hz() > 0.0 && theirs.buzzer_tone_hz() > 0.0) {
    add("buzzer_tone", "Hz", mine.buzzer_tone_hz(), theirs.buzzer_tone_hz());
  }
  for (const auto& [device, offset_us] : mine.clock_offset_us()) {
    const auto t = theirs.clock_offset_us().find(device);
    if (t != theirs.clock_offset_us().end()) {
      add("clock_offset " + device, "us", static_cast<double>(offset_us), static_cast<double>(t->second));
    }
  }
  for (const v1::ImuCalibration& imu : mine.imus()) {
    const auto t = std::find_if(theirs.imus().begin(), theirs.imus().end(),
                                [&](const v1::ImuCalibration& g) { return g.device_id() == imu.device_id(); });
    if (t == theirs.imus().end() || !imu.has_gyro_bias_rad_s()) continue;
    const double error = (vec_of(imu.gyro_bias_rad_s()) - vec_of(t->gyro_bias_rad_s())).norm() * kDegPerRad;
    report.calibration.push_back({"gyro_bias " + imu.device_id(), "deg/s", 0.0, 0.0, error});
  }
}

// Text tables: columns padded to their widest cell.
class Table {
 public:
  explicit Table(std::vector<std::string> header) { rows_.push_back(std::move(header)); }
  void add(std::vector<std::string> row) { rows_.push_back(std::move(row)); }
  std::size_t rows() const { return rows_.size() - 1; }
  std::string str() const {
    std::vector<std::size_t> width(rows_.front().size(), 0);
    for (const auto& row : rows_) {
      for (std::size_t c = 0; c < row.size(); ++c) width[c] = std::max(width[c], row[c].size());
    }
    std::string out;
    for (const auto& row : rows_) {
      std::string line;
      for (std::size_t c = 0; c < row.size(); ++c) {
        line += (c ? "  " : "") + row[c] + std::string(width[c] - row[c].size(), ' ');
      }
      while (!line.empty() && line.back() == ' ') line.pop_back();
      out += line + "\n";
    }
    return out;
  }

 private:
  std::vector<std::vector<std::string>> rows_;
};

std::string fixed(double value, int decimals) {
  if (!std::isfinite(value)) return "-";
  char buffer[64];
  std::snprintf(buffer, sizeof buffer, "%.*f", decimals, value);
  return buffer;
}

}  // namespace

const AngleScore* ScoreReport::orientation(const std::string& stream, const std::string& key) const {
  for (const auto& s : orientations) {
    if (s.stream == stream && s.key == key) return &s;
  }
  return nullptr;
}
const PositionScore* ScoreReport::position(const std::string& device_id, const std::string& subset) const {
  for (const auto& s : positions) {
    if (s.device_id == device_id && s.subset == subset) return &s;
  }
  return nullptr;
}
const CalibrationScore* ScoreReport::calibration_value(const std::string& name) const {
  for (const auto& s : calibration) {
    if (s.name == name) return &s;
  }
  return nullptr;
}

std::vector<OcclusionRow> read_gt_occlusion(const fs::path& gt_directory) {
  std::vector<OcclusionRow> rows;
  const fs::path path = gt_directory / "occlusion.csv";
  if (!fs::exists(path)) return rows;
  session::CsvReader csv(path, "occlusion.csv",
                         {"t_us", "arm", "forearm_visible_fraction", "forearm_occluded", "strap_visible"});
  while (csv.next()) {
    OcclusionRow row;
    row.t_us = session::parse_int64(csv.at(0), csv.field(0));
    if (!v1::Arm_Parse(std::string(csv.at(1)), &row.arm)) throw_invalid(csv.field(1), "is not LEFT or RIGHT");
    if (csv.at(3) != "0" && csv.at(3) != "1") throw_invalid(csv.field(3), "is not 0 or 1");
    row.occluded = csv.at(3) == "1";
    rows.push_back(row);
  }
  return rows;
}

ScoreReport score_results(const session::ResultDirectory& result, const session::ResultDirectory& truth,
                          const std::vector<OcclusionRow>& occlusion, const ScoreOptions& options) {
  if (result.files.empty()) {
    throw Error(ErrorCode::kNotFound, result.directory.string(), "holds none of the result files");
  }
  ScoreReport report;
  score_orientation_folders(result, truth, options, report);
  score_forearms(result, truth, options, report);
  score_positions(result, truth, occlusion, options, report);
  if (!result.smpl_joints.empty()) {
    require_truth(truth, layout::kSmplJointsCsv);
    score_joints(layout::kSmplJointsCsv, result.smpl_joints, truth.smpl_joints, smpl_groups(), options, report);
  }
  if (!result.camera_joints.empty()) {
    require_truth(truth, layout::kCameraJointsCsv);
    score_joints(layout::kCameraJointsCsv, result.camera_joints, truth.camera_joints, camera_groups(), options, report);
  }
  if (!result.joint_angles.empty()) {
    require_truth(truth, layout::kJointAnglesCsv);
    score_joint_angles(result, truth, options, report);
  }
  if (result.has(layout::kRepetitionsCsv)) {
    require_truth(truth, layout::kRepetitionsCsv);
    score_repetitions(result, truth, report);
  }
  score_calibration(result, truth, report);
  for (const std::string& file : truth.files) {
    if (!result.has(file) && file.find('/') == std::string::npos) report.notes.push_back(file + ": not in the results");
  }
  return report;
}

ScoreReport score_directories(const fs::path& result_directory, const fs::path& gt_directory,
                              const ScoreOptions& options) {
  const session::ResultDirectory result = session::read_result_files(result_directory);
  const session::ResultDirectory truth = session::read_result_files(gt_directory);
  return score_results(result, truth, read_gt_occlusion(gt_directory), options);
}

std::string format_score_report(const ScoreReport& report) {
  std::ostringstream out;
  if (!report.orientations.empty()) {
    out << "Orientation error, paper 1 eqs. 14-15 (deg)\n";
    Table t({"stream", "key", "n", "RMS", "max", "heading RMS", "unmatched"});
    for (const auto& s : report.orientations) {
      t.add({s.stream, s.key, std::to_string(s.deg.count), fixed(s.deg.rms, 2), fixed(s.deg.max, 2),
             s.heading_deg.count ? fixed(s.heading_deg.rms, 2) : "", std::to_string(s.unmatched)});
    }
    out << t.str() << "\n";
    Table c({"stream", "key", "n", "confident", "confident RMS", "confident max", "confident > 15", "within 99 % bound",
             "first confident (s)"});
    for (const auto& s : report.orientations) {
      if (!s.with_confidence) continue;
      c.add({s.stream, s.key, std::to_string(s.with_confidence), std::to_string(s.confident_deg.count),
             s.confident_deg.count ? fixed(s.confident_deg.rms, 2) : "-",
             s.confident_deg.count ? fixed(s.confident_deg.max, 2) : "-", std::to_string(s.confident_beyond_15_deg),
             s.with_uncertainty ? std::to_string(s.within_predicted_bound) + "/" + std::to_string(s.with_uncertainty)
                                : "-",
             s.first_confident_s ? fixed(*s.first_confident_s, 1) : "never"});
    }
    if (c.rows() > 0)
      out << "Confidence of the orientations (confident: >= 0.5, predicted within 15 deg)\n" << c.str() << "\n";
  }
  if (!report.positions.empty()) {
    out << "IMU position error (m)\n";
    Table t({"device", "frames", "n", "RMS", "max", "unmatched"});
    for (const auto& s : report.positions) {
      t.add({s.device_id, s.subset, std::to_string(s.m.count), fixed(s.m.rms, 4), fixed(s.m.max, 4),
             std::to_string(s.unmatched)});
    }
    out << t.str() << "\n";
  }
  if (!report.joints.empty()) {
    out << "Joint error per group (m)\n";
    Table t({"stream", "group", "n", "mean", "max"});
    for (const auto& s : report.joints) {
      t.add({s.stream, s.group, std::to_string(s.count), fixed(s.mean_m, 4), fixed(s.max_m, 4)});
    }
    out << t.str() << "\n";
  }
  if (!report.calibration.empty()) {
    out << "Calibration vs truth (angles: the rotation between result and truth)\n";
    Table t({"value", "unit", "result", "truth", "error", "claimed sigma"});
    for (const auto& s : report.calibration) {
      const int decimals = s.unit == "m" ? 4 : s.unit == "us" ? 0 : 2;
      const bool angle = s.unit == "deg" || s.unit == "deg/s";
      t.add({s.name, s.unit, angle ? "" : fixed(s.result, decimals), angle ? "" : fixed(s.truth, decimals),
             fixed(s.error, decimals), s.uncertainty > 0.0 ? fixed(s.uncertainty, decimals) : ""});
    }
    out << t.str() << "\n";
  }
  if (!report.joint_angles.empty()) {
    out << "ISB joint angle error (deg)\n";
    Table t({"angle", "n", "RMS", "max", "confident n", "confident RMS", "confident max", "undefined", "unmatched"});
    for (const auto& s : report.joint_angles) {
      t.add({s.angle, std::to_string(s.deg.count), fixed(s.deg.rms, 2), fixed(s.deg.max, 2),
             std::to_string(s.confident_deg.count), fixed(s.confident_deg.rms, 2), fixed(s.confident_deg.max, 2),
             std::to_string(s.result_undefined), std::to_string(s.unmatched)});
    }
    out << t.str() << "\n";
  }
  if (report.repetitions) {
    const RepetitionScore& r = *report.repetitions;
    out << "Repetitions (counted) and range of motion per repetition (deg)\n";
    Table t({"angle", "true angle", "count", "true count", "matched", "ROM error RMS", "ROM error max", "confident",
             "confident RMS", "confident max"});
    t.add({r.result_angle, r.truth_angle, std::to_string(r.result_count), std::to_string(r.truth_count),
           std::to_string(r.matched), fixed(r.range_deg.rms, 2), fixed(r.range_deg.max, 2),
           std::to_string(r.confident_range_deg.count),
           r.confident_range_deg.count > 0 ? fixed(r.confident_range_deg.rms, 2) : "-",
           r.confident_range_deg.count > 0 ? fixed(r.confident_range_deg.max, 2) : "-"});
    out << t.str() << "\n";
  }
  for (const std::string& note : report.notes) out << "note: " << note << "\n";
  return out.str();
}

}  // namespace posefuse::eval
