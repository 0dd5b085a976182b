#include "session/result_files.hpp"

#include <cstdio>

#include "body/smpl_model.hpp"
#include "common/error.hpp"
#include "measures/joint_angles.hpp"
#include "session/directory_layout.hpp"
#include "session/file_bytes.hpp"
#include "session/json_message.hpp"
#include "session/session_validator.hpp"

namespace posefuse::session {

namespace {

void require_device_id(const std::string& device_id, const std::string& field) {
  // The id becomes a file name or a CSV field: accept only what the session format allows.
  if (!is_valid_device_id(device_id)) {
    throw Error(ErrorCode::kInvalidArgument, field,
                "device id " + session::quoted(device_id) + " is not a safe file name");
  }
}

std::vector<std::string> vec3_fields(const v1::Vec3& v) {
  return {format_double(v.x()), format_double(v.y()), format_double(v.z())};
}

template <typename Joints>
void write_joints(CsvWriter& csv, std::int64_t t_us, const Joints& joints, const char* const* names) {
  for (int j = 0; j < joints.size(); ++j) {
    const v1::JointEstimate& joint = joints[j];
    csv.row({std::to_string(t_us), std::to_string(j), names[j], format_double(joint.position_m().x()),
             format_double(joint.position_m().y()), format_double(joint.position_m().z()),
             v1::Source_Name(joint.source()), format_double(joint.confidence())});
  }
}

}  // namespace

namespace result_layout {
std::vector<std::string> joint_angle_columns() {
  std::vector<std::string> columns{"t_s"};
  for (int i = 0; i < measures::kAngleCount; ++i)
    columns.emplace_back(measures::angle_name(static_cast<measures::Angle>(i)));
  for (int i = 0; i < measures::kAngleCount; ++i)
    columns.push_back(std::string(measures::angle_name(static_cast<measures::Angle>(i))) + "_confidence");
  return columns;
}
}  // namespace result_layout

ResultFiles::ResultFiles(const std::filesystem::path& directory) : directory_(directory) {
  std::error_code error;
  std::filesystem::create_directories(directory_ / result_layout::kImuOrientationDir, error);
  if (error) {
    throw Error(ErrorCode::kFailedPrecondition, directory_.string(),
                "cannot create the output directory: " + error.message());
  }
}

ResultFiles::~ResultFiles() = default;

void ResultFiles::write_orientations(const v1::ImuOrientationBatch& batch) {
  require_device_id(batch.device_id(), "imu_orientations.device_id");
  if (batch.w_from_a_size() != 4 * batch.t_us_size() || batch.uncertainty_rad_size() != batch.t_us_size() ||
      batch.confidence_size() != batch.t_us_size()) {
    throw Error(ErrorCode::kInvalidArgument, "imu_orientations.W_from_A",
                "has " + std::to_string(batch.w_from_a_size()) + " values, " +
                    std::to_string(batch.uncertainty_rad_size()) + " uncertainties and " +
                    std::to_string(batch.confidence_size()) + " confidences for " + std::to_string(batch.t_us_size()) +
                    " samples");
  }
  auto& csv = orientations_[batch.device_id()];
  if (!csv) {
    csv = std::make_unique<CsvWriter>(directory_ / result_layout::kImuOrientationDir / (batch.device_id() + ".csv"),
                                      result_layout::kOrientationColumns);
  }
  for (int i = 0; i < batch.t_us_size(); ++i) {
    csv->row({std::to_string(batch.t_us(i)), format_double(batch.w_from_a(4 * i)),
              format_double(batch.w_from_a(4 * i + 1)), format_double(batch.w_from_a(4 * i + 2)),
              format_double(batch.w_from_a(4 * i + 3)), format_double(batch.uncertainty_rad(i)),
              format_double(batch.confidence(i))});
  }
  orientation_samples_ += static_cast<std::uint64_t>(batch.t_us_size());
}

void ResultFiles::write_forearm_orientations(const v1::ForearmOrientationBatch& batch) {
  require_device_id(batch.device_id(), "forearm_orientations.device_id");
  if (batch.k_from_f_size() != 4 * batch.t_us_size() || batch.pronation_rad_size() != batch.t_us_size() ||
      batch.uncertainty_rad_size() != batch.t_us_size() || batch.confidence_size() != batch.t_us_size()) {
    throw Error(ErrorCode::kInvalidArgument, "forearm_orientations.K_from_F",
                "has " + std::to_string(batch.k_from_f_size()) + " values, " +
                    std::to_string(batch.pronation_rad_size()) + " angles, " +
                    std::to_string(batch.uncertainty_rad_size()) + " uncertainties and " +
                    std::to_string(batch.confidence_size()) + " confidences for " + std::to_string(batch.t_us_size()) +
                    " samples");
  }
  auto& csv = (batch.offline() ? offline_forearm_orientations_ : forearm_orientations_)[batch.device_id()];
  if (!csv) {
    const std::filesystem::path folder = directory_ / (batch.offline() ? result_layout::kForearmOrientationOfflineDir
                                                                       : result_layout::kForearmOrientationDir);
    std::error_code error;
    std::filesystem::create_directories(folder, error);
    if (error) {
      throw Error(ErrorCode::kFailedPrecondition, folder.string(), "cannot create: " + error.message());
    }
    csv = std::make_unique<CsvWriter>(folder / (batch.device_id() + ".csv"), result_layout::kForearmOrientationColumns);
  }
  for (int i = 0; i < batch.t_us_size(); ++i) {
    csv->row({std::to_string(batch.t_us(i)), format_double(batch.k_from_f(4 * i)),
              format_double(batch.k_from_f(4 * i + 1)), format_double(batch.k_from_f(4 * i + 2)),
              format_double(batch.k_from_f(4 * i + 3)), format_double(batch.pronation_rad(i)),
              format_double(batch.uncertainty_rad(i)), format_double(batch.confidence(i))});
  }
  (batch.offline() ? offline_forearm_samples_ : forearm_samples_) += static_cast<std::uint64_t>(batch.t_us_size());
}

CsvWriter& ResultFiles::opened_file(std::optional<CsvWriter>& file, const char* name,
                                    const std::vector<std::string>& columns) {
  if (!file) file.emplace(directory_ / name, columns);
  return *file;
}

void ResultFiles::write_frame(const v1::FrameResult& frame) {
  if (frame.smpl_joints_size() > body::kNumJoints) {
    throw Error(ErrorCode::kInvalidArgument, "frame.smpl_joints",
                "has " + std::to_string(frame.smpl_joints_size()) + " joints, at most 24");
  }
  if (frame.camera_joints_size() > kSkeletonJointCount) {
    throw Error(ErrorCode::kInvalidArgument, "frame.camera_joints",
                "has " + std::to_string(frame.camera_joints_size()) + " joints, at most 25");
  }
  if (frame.smpl_joint_rotations_size() != 0 && frame.smpl_joint_rotations_size() != body::kNumJoints) {
    throw Error(ErrorCode::kInvalidArgument, "frame.smpl_joint_rotations",
                "has " + std::to_string(frame.smpl_joint_rotations_size()) + " rotations, not 0 or 24");
  }
  for (const auto& position : frame.imu_positions()) {
    require_device_id(position.device_id(), "frame.imu_positions.device_id");
  }
  const std::int64_t t = frame.t_us();
  if (frame.smpl_joints_size() > 0) {
    write_joints(opened_file(smpl_joints_, result_layout::kSmplJointsCsv, result_layout::kJointColumns), t,
                 frame.smpl_joints(), body::smpl_joint_names().data());
  }
  for (int j = 0; j < frame.smpl_joint_rotations_size(); ++j) {
    const v1::Quaternion& q = frame.smpl_joint_rotations(j);
    opened_file(smpl_rotations_, result_layout::kSmplJointRotationsCsv, result_layout::kJointRotationColumns)
        .row({std::to_string(t), std::to_string(j), body::smpl_joint_names()[static_cast<std::size_t>(j)],
              format_double(q.w()), format_double(q.x()), format_double(q.y()), format_double(q.z())});
  }
  if (frame.smpl_joint_rotations_size() > 0) {  // a body-fit frame: its fit's energy E
    opened_file(fit_energy_, result_layout::kFitEnergyCsv, result_layout::kFitEnergyColumns)
        .row({std::to_string(t), format_double(frame.fit_energy())});
  }
  if (frame.camera_joints_size() > 0) {
    write_joints(opened_file(camera_joints_, result_layout::kCameraJointsCsv, result_layout::kJointColumns), t,
                 frame.camera_joints(), layout::kKinectJointNames.data());
  }
  for (const auto& forearm : frame.forearms()) {
    const v1::Quaternion& q = forearm.k_from_f();
    opened_file(forearms_, result_layout::kForearmsCsv, result_layout::kForearmColumns)
        .row({std::to_string(t), v1::Arm_Name(forearm.arm()), format_double(q.w()), format_double(q.x()),
              format_double(q.y()), format_double(q.z()), format_double(forearm.pronation_rad()),
              v1::Source_Name(forearm.source()), format_double(forearm.confidence())});
  }
  for (const auto& position : frame.imu_positions()) {
    std::vector<std::string> row{std::to_string(t), position.device_id()};
    for (std::string& v : vec3_fields(position.position_m())) row.push_back(std::move(v));
    row.push_back(v1::Source_Name(position.source()));
    opened_file(imu_positions_, result_layout::kImuPositionsCsv, result_layout::kImuPositionColumns).row(row);
    ++imu_positions_count_;
  }
  ++frames_;
}

void ResultFiles::write_segment(const v1::RecoveredSegment& segment) {
  require_device_id(segment.device_id(), "recovered_segment.device_id");
  CsvWriter& csv =
      opened_file(segments_, result_layout::kRecoveredSegmentsCsv, result_layout::kRecoveredSegmentColumns);
  for (const v1::RecoveredSegment::Sample& s : segment.samples()) {
    std::vector<std::string> row{segment.device_id(), v1::RecoveredSegment::Method_Name(segment.method()),
                                 std::to_string(segment.t_start_us()), std::to_string(segment.t_end_us()),
                                 std::to_string(s.t_us())};
    for (const v1::Vec3* v : {&s.imu_m(), &s.elbow_m(), &s.wrist_m()}) {
      for (std::string& f : vec3_fields(*v)) row.push_back(std::move(f));
    }
    for (const double q : {s.k_from_f().w(), s.k_from_f().x(), s.k_from_f().y(), s.k_from_f().z()}) {
      row.push_back(format_double(q));
    }
    csv.row(row);
  }
  ++recovered_segments_;
}

void ResultFiles::write_angles(const v1::FrameAngles& angles) {
  if (angles.angles_size() != measures::kAngleCount) {
    throw Error(
        ErrorCode::kInvalidArgument, "joint_angles.angles",
        "has " + std::to_string(angles.angles_size()) + " angles, expected " + std::to_string(measures::kAngleCount));
  }
  std::vector<std::string> row{format_seconds(angles.t_us())};
  for (int i = 0; i < measures::kAngleCount; ++i) {
    const v1::JointAngle& a = angles.angles(i);
    if (a.kind() != static_cast<v1::JointAngleKind>(i + 1)) {
      throw Error(ErrorCode::kInvalidArgument, "joint_angles.angles[" + std::to_string(i) + "].kind",
                  "is " + v1::JointAngleKind_Name(a.kind()) + ", expected " +
                      v1::JointAngleKind_Name(static_cast<v1::JointAngleKind>(i + 1)));
    }
    row.push_back(a.defined() ? format_double(a.deg()) : "");
  }
  for (const v1::JointAngle& a : angles.angles()) row.push_back(format_double(a.defined() ? a.confidence() : 0.0));
  opened_file(angles_, result_layout::kJointAnglesCsv, result_layout::joint_angle_columns()).row(row);
}

void ResultFiles::write_repetitions(const v1::RepetitionSummary& summary) {
  const std::string angle = summary.angle() == v1::JOINT_ANGLE_UNSPECIFIED
                                ? std::string("unspecified")
                                : std::string(measures::angle_name(static_cast<measures::Angle>(summary.angle() - 1)));
  CsvWriter csv(directory_ / result_layout::kRepetitionsCsv, result_layout::kRepetitionColumns);
  int index = 0;
  for (const v1::Repetition& r : summary.repetitions()) {
    csv.row({angle, std::to_string(index++), format_seconds(r.t_start_us()), format_seconds(r.t_peak_us()),
             format_seconds(r.t_end_us()), format_double(r.min_deg()), format_double(r.max_deg()),
             format_double(r.range_deg()), format_double(r.peak_speed_deg_s()), format_double(r.duration_s()),
             r.partial() ? "0" : "1", format_double(r.confidence()), format_double(r.cut_ambiguity_deg())});
  }
  csv.close();
  v1::RepetitionSummary totals = summary;
  totals.clear_repetitions();
  write_file_bytes(directory_ / result_layout::kRepetitionSummaryJson, message_to_json(totals));
}

void ResultFiles::write_calibration(const v1::CalibrationReport& report) {
  write_file_bytes(directory_ / result_layout::kCalibrationJson, message_to_json(report));
}

void ResultFiles::close() {
  for (auto& [device, csv] : orientations_) csv->close();
  for (auto& [device, csv] : forearm_orientations_) csv->close();
  for (auto* file : {&smpl_joints_, &smpl_rotations_, &fit_energy_, &camera_joints_, &forearms_, &imu_positions_,
                     &segments_, &angles_}) {
    if (*file) (*file)->close();
  }
}

}  // namespace posefuse::session
