#include "client/result_writer.hpp"

#include <fstream>

#include "common/error.hpp"
#include "session/file_bytes.hpp"
#include "session/json_message.hpp"

namespace posefuse::client {

ResultWriter::ResultWriter(const std::filesystem::path& directory) : directory_(directory), files_(directory) {
  warnings_file_ = std::make_unique<std::ofstream>(directory_ / "warnings.txt");
  if (!*warnings_file_) {
    throw Error(ErrorCode::kFailedPrecondition, (directory_ / "warnings.txt").string(), "cannot create");
  }
}

ResultWriter::~ResultWriter() = default;

void ResultWriter::write(const v1::FitResult& result) {
  switch (result.result_case()) {
    case v1::FitResult::kImuOrientations: files_.write_orientations(result.imu_orientations()); break;
    case v1::FitResult::kForearmOrientations: files_.write_forearm_orientations(result.forearm_orientations()); break;
    case v1::FitResult::kFrame: files_.write_frame(result.frame()); break;
    case v1::FitResult::kRecoveredSegment: files_.write_segment(result.recovered_segment()); break;
    case v1::FitResult::kCalibration: files_.write_calibration(result.calibration()); break;
    case v1::FitResult::kJointAngles: files_.write_angles(result.joint_angles()); break;
    case v1::FitResult::kRepetitions: files_.write_repetitions(result.repetitions()); break;
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
      note("error", result.item_error().code(), result.item_error().field(), result.item_error().message());
      break;
    default: break;  // progress is shown, not stored
  }
}

void ResultWriter::note(const std::string& kind, const std::string& code, const std::string& field,
                        const std::string& message) {
  *warnings_file_ << kind << " [" << code << "] " << field << ": " << message << '\n';
}

void ResultWriter::finish() {
  files_.close();
  warnings_file_->flush();
  if (!*warnings_file_) {
    throw Error(ErrorCode::kDataLoss, (directory_ / "warnings.txt").string(), "write failed");
  }
}

}  // namespace posefuse::client
