#include "client/result_writer.hpp"

#include <fstream>

#include "common/error.hpp"
#include "session/file_bytes.hpp"
#include "session/json_message.hpp"
#include "session/session_validator.hpp"

namespace posefuse::client {

namespace {
const char* const kOrientationDir = "imu_orientations";
}

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
    default: break;  // progress is shown, not stored; frames etc. come with their stages
  }
}

void ResultWriter::write_orientations(const v1::ImuOrientationBatch& batch) {
  // The id becomes a file name: accept only what the session format allows.
  if (!session::is_valid_device_id(batch.device_id())) {
    throw Error(ErrorCode::kInvalidArgument, "imu_orientations.device_id",
                "the server sent a device id that is not a safe file name");
  }
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

void ResultWriter::note(const std::string& kind, const std::string& code,
                        const std::string& field, const std::string& message) {
  *warnings_file_ << kind << " [" << code << "] " << field << ": " << message << '\n';
}

void ResultWriter::finish() {
  for (auto& [device, csv] : orientations_) csv->close();
  warnings_file_->flush();
  if (!*warnings_file_) {
    throw Error(ErrorCode::kDataLoss, (directory_ / "warnings.txt").string(), "write failed");
  }
}

}  // namespace posefuse::client
