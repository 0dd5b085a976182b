#include "session/result_files.hpp"

#include "body/smpl_model.hpp"
#include "common/error.hpp"
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
  if (batch.w_from_a_size() != 4 * batch.t_us_size()) {
    throw Error(ErrorCode::kInvalidArgument, "imu_orientations.W_from_A",
                "has " + std::to_string(batch.w_from_a_size()) + " values for " +
                    std::to_string(batch.t_us_size()) + " samples");
  }
  auto& csv = orientations_[batch.device_id()];
  if (!csv) {
    csv = std::make_unique<CsvWriter>(
        directory_ / result_layout::kImuOrientationDir / (batch.device_id() + ".csv"),
        result_layout::kOrientationColumns);
  }
  for (int i = 0; i < batch.t_us_size(); ++i) {
    csv->row({std::to_string(batch.t_us(i)), format_double(batch.w_from_a(4 * i)),
              format_double(batch.w_from_a(4 * i + 1)), format_double(batch.w_from_a(4 * i + 2)),
              format_double(batch.w_from_a(4 * i + 3))});
  }
  orientation_samples_ += static_cast<std::uint64_t>(batch.t_us_size());
}

CsvWriter& ResultFiles::frame_file(std::optional<CsvWriter>& file, const char* name,
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
  for (const auto& position : frame.imu_positions()) {
    require_device_id(position.device_id(), "frame.imu_positions.device_id");
  }
  const std::int64_t t = frame.t_us();
  if (frame.smpl_joints_size() > 0) {
    write_joints(frame_file(smpl_joints_, result_layout::kSmplJointsCsv, result_layout::kJointColumns), t,
                 frame.smpl_joints(), body::smpl_joint_names().data());
  }
  if (frame.camera_joints_size() > 0) {
    write_joints(frame_file(camera_joints_, result_layout::kCameraJointsCsv, result_layout::kJointColumns),
                 t, frame.camera_joints(), layout::kKinectJointNames.data());
  }
  for (const auto& forearm : frame.forearms()) {
    const v1::Quaternion& q = forearm.k_from_f();
    frame_file(forearms_, result_layout::kForearmsCsv, result_layout::kForearmColumns)
        .row({std::to_string(t), v1::Arm_Name(forearm.arm()), format_double(q.w()), format_double(q.x()),
              format_double(q.y()), format_double(q.z()), format_double(forearm.pronation_rad()),
              v1::Source_Name(forearm.source()), format_double(forearm.confidence())});
  }
  for (const auto& position : frame.imu_positions()) {
    frame_file(imu_positions_, result_layout::kImuPositionsCsv, result_layout::kImuPositionColumns)
        .row({std::to_string(t), position.device_id(), format_double(position.position_m().x()),
              format_double(position.position_m().y()), format_double(position.position_m().z()),
              v1::Source_Name(position.source())});
  }
  ++frames_;
}

void ResultFiles::write_calibration(const v1::CalibrationReport& report) {
  write_file_bytes(directory_ / result_layout::kCalibrationJson, message_to_json(report));
}

void ResultFiles::close() {
  for (auto& [device, csv] : orientations_) csv->close();
  for (auto* file : {&smpl_joints_, &camera_joints_, &forearms_, &imu_positions_}) {
    if (*file) (*file)->close();
  }
}

}  // namespace posefuse::session
