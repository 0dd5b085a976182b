#include "client/result_writer.hpp"

#include <fstream>

#include "common/error.hpp"
#include "session/file_bytes.hpp"
#include "session/json_message.hpp"
#include "session/session_validator.hpp"

namespace posefuse::client {

namespace {
const char* const kOrientationDir = "imu_orientations";
const char* const kForearmDir = "forearm_orientations";

// The id becomes a file name: accept only what the session format allows.
void check_device_id(const std::string& id, const std::string& field) {
  if (!session::is_valid_device_id(id)) {
    throw Error(ErrorCode::kInvalidArgument, field, "the server sent a device id that is not a safe file name");
  }
}

std::vector<std::string> vec3_fields(const v1::Vec3& v) {
  return {session::format_double(v.x()), session::format_double(v.y()), session::format_double(v.z())};
}
}  // namespace

ResultWriter::ResultWriter(const std::filesystem::path& directory) : directory_(directory) {
  std::error_code error;
  std::filesystem::create_directories(directory_ / kOrientationDir, error);
  if (error) {
    throw Error(ErrorCode::kFailedPrecondition, directory_.string(),
                "cannot create the output directory: " + error.message());
  }
  warnings_file_ = std::make_unique<std::ofstream>(directory_ / "warnings.txt");
  if (!*warnings_file_) {
    throw Error(ErrorCode::kFailedPrecondition, (directory_ / "warnings.txt").string(),
                "cannot create");
  }
}

ResultWriter::~ResultWriter() = default;

void ResultWriter::write(const v1::FitResult& result) {
  switch (result.result_case()) {
    case v1::FitResult::kImuOrientations: write_orientations(result.imu_orientations()); break;
    case v1::FitResult::kForearmOrientations: write_forearm_orientations(result.forearm_orientations()); break;
    case v1::FitResult::kFrame: write_frame(result.frame()); break;
    case v1::FitResult::kRecoveredSegment: write_segment(result.recovered_segment()); break;
    case v1::FitResult::kCalibration:
      session::write_file_bytes(directory_ / "calibration.json",
                                session::message_to_json(result.calibration()));
      break;
    case v1::FitResult::kSummary:
      summary_ = result.summary();
      have_summary_ = true;
      session::write_file_bytes(directory_ / "summary.json", session::message_to_json(summary_));
      break;
    case v1::FitResult::kWarning:
      ++warnings_;
      note("warning", result.warning().code(), result.warning().field(), result.warning().message());
      break;
    case v1::FitResult::kItemError:
      ++item_errors_;
      note("error", result.item_error().code(), result.item_error().field(),
           result.item_error().message());
      break;
    default: break;  // progress is shown, not stored
  }
}

void ResultWriter::write_orientations(const v1::ImuOrientationBatch& batch) {
  check_device_id(batch.device_id(), "imu_orientations.device_id");
  if (batch.w_from_a_size() != 4 * batch.t_us_size()) {
    throw Error(ErrorCode::kInvalidArgument, "imu_orientations.W_from_A",
                "has " + std::to_string(batch.w_from_a_size()) + " values for " +
                    std::to_string(batch.t_us_size()) + " samples");
  }
  auto& csv = orientations_[batch.device_id()];
  if (!csv) {
    csv = std::make_unique<session::CsvWriter>(
        directory_ / kOrientationDir / (batch.device_id() + ".csv"),
        std::vector<std::string>{"t_us", "w", "x", "y", "z"});
  }
  for (int i = 0; i < batch.t_us_size(); ++i) {
    csv->row({std::to_string(batch.t_us(i)), session::format_double(batch.w_from_a(4 * i)),
              session::format_double(batch.w_from_a(4 * i + 1)),
              session::format_double(batch.w_from_a(4 * i + 2)),
              session::format_double(batch.w_from_a(4 * i + 3))});
  }
  orientation_samples_ += static_cast<std::uint64_t>(batch.t_us_size());
}

void ResultWriter::write_forearm_orientations(const v1::ForearmOrientationBatch& batch) {
  check_device_id(batch.device_id(), "forearm_orientations.device_id");
  if (batch.k_from_f_size() != 4 * batch.t_us_size() || batch.pronation_rad_size() != batch.t_us_size()) {
    throw Error(ErrorCode::kInvalidArgument, "forearm_orientations.K_from_F",
                "has " + std::to_string(batch.k_from_f_size()) + " values and " +
                    std::to_string(batch.pronation_rad_size()) + " angles for " + std::to_string(batch.t_us_size()) +
                    " samples");
  }
  auto& csv = forearm_orientations_[batch.device_id()];
  if (!csv) {
    std::error_code error;
    std::filesystem::create_directories(directory_ / kForearmDir, error);
    if (error) {
      throw Error(ErrorCode::kFailedPrecondition, (directory_ / kForearmDir).string(),
                  "cannot create: " + error.message());
    }
    csv = std::make_unique<session::CsvWriter>(directory_ / kForearmDir / (batch.device_id() + ".csv"),
                                               std::vector<std::string>{"t_us", "w", "x", "y", "z", "pronation_rad"});
  }
  for (int i = 0; i < batch.t_us_size(); ++i) {
    csv->row({std::to_string(batch.t_us(i)), session::format_double(batch.k_from_f(4 * i)),
              session::format_double(batch.k_from_f(4 * i + 1)), session::format_double(batch.k_from_f(4 * i + 2)),
              session::format_double(batch.k_from_f(4 * i + 3)), session::format_double(batch.pronation_rad(i))});
  }
  forearm_samples_ += static_cast<std::uint64_t>(batch.t_us_size());
}

void ResultWriter::write_frame(const v1::FrameResult& frame) {
  for (const v1::ImuPosition& p : frame.imu_positions()) {
    check_device_id(p.device_id(), "frame.imu_positions.device_id");
    if (!imu_positions_file_) {
      imu_positions_file_ = std::make_unique<session::CsvWriter>(
          directory_ / "imu_positions.csv",
          std::vector<std::string>{"t_us", "device_id", "x_m", "y_m", "z_m", "source"});
    }
    std::vector<std::string> row{std::to_string(frame.t_us()), p.device_id()};
    for (std::string& v : vec3_fields(p.position_m())) row.push_back(std::move(v));
    row.push_back(v1::Source_Name(p.source()));
    imu_positions_file_->row(row);
    ++imu_positions_;
  }
}

void ResultWriter::write_segment(const v1::RecoveredSegment& segment) {
  check_device_id(segment.device_id(), "recovered_segment.device_id");
  if (!segments_file_) {
    segments_file_ = std::make_unique<session::CsvWriter>(
        directory_ / "recovered_segments.csv",
        std::vector<std::string>{"device_id", "method", "t_start_us", "t_end_us", "t_us", "imu_x_m", "imu_y_m",
                                 "imu_z_m", "elbow_x_m", "elbow_y_m", "elbow_z_m", "wrist_x_m", "wrist_y_m",
                                 "wrist_z_m", "w", "x", "y", "z"});
  }
  for (const v1::RecoveredSegment::Sample& s : segment.samples()) {
    std::vector<std::string> row{segment.device_id(), v1::RecoveredSegment::Method_Name(segment.method()),
                                 std::to_string(segment.t_start_us()), std::to_string(segment.t_end_us()),
                                 std::to_string(s.t_us())};
    for (const v1::Vec3* v : {&s.imu_m(), &s.elbow_m(), &s.wrist_m()}) {
      for (std::string& f : vec3_fields(*v)) row.push_back(std::move(f));
    }
    for (const double q : {s.k_from_f().w(), s.k_from_f().x(), s.k_from_f().y(), s.k_from_f().z()}) {
      row.push_back(session::format_double(q));
    }
    segments_file_->row(row);
  }
  ++recovered_segments_;
}

void ResultWriter::note(const std::string& kind, const std::string& code,
                        const std::string& field, const std::string& message) {
  *warnings_file_ << kind << " [" << code << "] " << field << ": " << message << '\n';
}

void ResultWriter::finish() {
  for (auto& [device, csv] : orientations_) csv->close();
  for (auto& [device, csv] : forearm_orientations_) csv->close();
  if (imu_positions_file_) imu_positions_file_->close();
  if (segments_file_) segments_file_->close();
  warnings_file_->flush();
  if (!*warnings_file_) {
    throw Error(ErrorCode::kDataLoss, (directory_ / "warnings.txt").string(), "write failed");
  }
}

}  // namespace posefuse::client
