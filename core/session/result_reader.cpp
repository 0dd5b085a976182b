#include "session/result_reader.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <utility>

#include "body/smpl_model.hpp"
#include "common/error.hpp"
#include "measures/joint_angles.hpp"
#include "session/directory_layout.hpp"
#include "session/json_message.hpp"
#include "session/recording_file.hpp"
#include "session/result_files.hpp"
#include "session/session_validator.hpp"
#include "session/text_fields.hpp"

namespace posefuse::session {

namespace {

namespace fs = std::filesystem;

// The result directory being read: every file is opened beneath its descriptor, without
// following links, and only regular files are read (recording_file.hpp), so a link or a FIFO
// in a result directory is an error rather than a read elsewhere or a hang.
struct Reading {
  UniqueFd directory;
  ResultDirectory result;
};

// calibration.json is a few kilobytes.
constexpr std::uint64_t kMaxJsonBytes = 1u << 20;

// One opened result file: the CsvReader plus typed, checked field access.
class ResultCsv {
 public:
  ResultCsv(int directory, const std::string& name, const std::vector<std::string>& columns)
      : csv_(open_stream_beneath(directory, name), name, columns) {}
  bool next() { return csv_.next(); }
  std::string text(std::size_t c) const { return std::string(csv_.at(c)); }
  std::int64_t int64(std::size_t c) const { return parse_int64(csv_.at(c), csv_.field(c)); }
  double number(std::size_t c) const {
    const double v = parse_double(csv_.at(c), csv_.field(c));
    if (!std::isfinite(v)) throw_invalid(csv_.field(c), "is " + session::quoted(csv_.at(c)) + ", not a finite number");
    return v;
  }
  // A finite number or "nan" (a value the method could not give, e.g. pronation without a
  // calibration pose).
  double number_or_nan(std::size_t c) const {
    const double v = parse_double(csv_.at(c), csv_.field(c));
    if (std::isinf(v)) throw_invalid(csv_.field(c), "is " + session::quoted(csv_.at(c)) + ", not a number or nan");
    return v;
  }
  geometry::Vec3 vec3(std::size_t c) const { return {number(c), number(c + 1), number(c + 2)}; }
  // A unit quaternion w x y z in columns c..c+3.
  geometry::Quat quat(std::size_t c) const {
    const geometry::Quat q(number(c), number(c + 1), number(c + 2), number(c + 3));
    if (std::abs(q.norm() - 1.0) > 1e-3) {
      throw_invalid(csv_.field(c), "quaternion has norm " + format_double(q.norm()) + ", not 1");
    }
    return q.normalized();
  }
  v1::Source source(std::size_t c) const {
    v1::Source s{};
    if (!v1::Source_Parse(text(c), &s))
      throw_invalid(csv_.field(c), session::quoted(csv_.at(c)) + " is not a Source name");
    return s;
  }
  v1::Arm arm(std::size_t c) const {
    v1::Arm a{};
    if (!v1::Arm_Parse(text(c), &a) || a == v1::ARM_UNSPECIFIED) {
      throw_invalid(csv_.field(c), session::quoted(csv_.at(c)) + " is not LEFT or RIGHT");
    }
    return a;
  }
  std::string device_id(std::size_t c) const {
    if (!is_valid_device_id(text(c))) throw_invalid(csv_.field(c), session::quoted(csv_.at(c)) + " is not a device id");
    return text(c);
  }
  // t_us of column c, which must not be earlier than `previous` (then updated).
  std::int64_t time_after(std::size_t c, std::int64_t& previous, bool first) const {
    const std::int64_t t = int64(c);
    if (!first && t < previous) {
      throw_invalid(csv_.field(c), std::to_string(t) + " is earlier than the previous " + std::to_string(previous));
    }
    previous = t;
    return t;
  }
  std::string field(std::size_t c) const { return csv_.field(c); }

 private:
  CsvReader csv_;
};

// Whether a file's header row is `columns` exactly (an earlier layout of it with fewer columns: an
// orientation file before each sample carried its uncertainty, repetitions.csv before each
// repetition carried its confidence or its cut's ambiguity).
bool has_header(int directory, const std::string& name, const std::vector<std::string>& columns) {
  const std::unique_ptr<std::istream> in = open_stream_beneath(directory, name);
  std::string header;
  std::getline(*in, header);
  if (!header.empty() && header.back() == '\r') header.pop_back();
  std::string expected;
  for (const std::string& c : columns) expected += (expected.empty() ? "" : ",") + c;
  return header == expected;
}

std::vector<TimedOrientation> read_orientations(int directory, const std::string& name, bool forearm) {
  namespace layout = result_layout;
  const std::vector<std::string>& older =
      forearm ? layout::kForearmOrientationColumnsWithoutUncertainty : layout::kOrientationColumnsWithoutUncertainty;
  const bool uncertainty = !has_header(directory, name, older);
  const std::vector<std::string>& today = forearm ? layout::kForearmOrientationColumns : layout::kOrientationColumns;
  ResultCsv csv(directory, name, uncertainty ? today : older);
  const int uncertainty_column = forearm ? 6 : 5;
  std::vector<TimedOrientation> rows;
  std::int64_t previous = 0;
  while (csv.next()) {
    TimedOrientation row;
    row.t_us = csv.time_after(0, previous, rows.empty());
    row.q = csv.quat(1);
    if (forearm) row.pronation_rad = csv.number_or_nan(5);
    if (uncertainty) {
      row.uncertainty_rad = csv.number(uncertainty_column);
      row.confidence = csv.number(uncertainty_column + 1);
    }
    rows.push_back(row);
  }
  return rows;
}

// imu_orientations/<id>.csv, forearm_orientations/<id>.csv or its offline folder's, keyed by id.
std::map<std::string, std::vector<TimedOrientation>> read_orientation_folder(Reading& in, const char* folder,
                                                                             bool forearm) {
  std::map<std::string, std::vector<TimedOrientation>> by_device;
  if (!has_entry(in.directory.get(), folder, FileKind::kDirectory)) return by_device;
  const UniqueFd dir = open_beneath(in.directory.get(), folder, folder);
  for (const std::string& file : list_directory(dir.get(), folder)) {
    if (fs::path(file).extension() != ".csv") continue;
    const std::string device = fs::path(file).stem().string();
    const std::string name = std::string(folder) + "/" + file;
    if (!is_valid_device_id(device)) throw_invalid(name, "file name is not a device id");
    by_device[device] = read_orientations(in.directory.get(), name, forearm);
    in.result.files.insert(name);
  }
  return by_device;
}

// The rows of one optional file of the layout: none when it is absent; else it is recorded in
// in.result.files and each row parsed by row_of(csv, rows so far).
template <typename Row, typename RowOf>
std::vector<Row> read_rows(Reading& in, const char* name, const std::vector<std::string>& columns, RowOf row_of) {
  std::vector<Row> rows;
  if (!has_entry(in.directory.get(), name, FileKind::kRegular)) return rows;
  in.result.files.insert(name);
  ResultCsv csv(in.directory.get(), name, columns);
  while (csv.next()) rows.push_back(row_of(csv, rows));
  return rows;
}

// Columns 1 and 2 of a joint file: the joint's index and its name, which must agree.
int joint_of(const ResultCsv& csv, int joint_count, const char* const* names) {
  const std::int64_t joint = csv.int64(1);
  if (joint < 0 || joint >= joint_count) {
    throw_invalid(csv.field(1), std::to_string(joint) + " is not in 0.." + std::to_string(joint_count - 1));
  }
  if (csv.text(2) != names[joint]) {
    throw_invalid(csv.field(2), session::quoted(csv.text(2)) + " is not joint " + std::to_string(joint) + "'s name " +
                                    session::quoted(names[joint]));
  }
  return static_cast<int>(joint);
}

std::vector<JointRow> read_joints(Reading& out, const char* name, int joint_count, const char* const* names) {
  std::int64_t previous = 0;
  return read_rows<JointRow>(out, name, result_layout::kJointColumns,
                             [&](const ResultCsv& csv, const std::vector<JointRow>& rows) {
                               JointRow row;
                               row.t_us = csv.time_after(0, previous, rows.empty());
                               row.joint = joint_of(csv, joint_count, names);
                               row.p_K = csv.vec3(3);
                               row.source = csv.source(6);
                               row.confidence = csv.number(7);
                               return row;
                             });
}

std::vector<JointRotationRow> read_joint_rotations(Reading& out) {
  std::int64_t previous = 0;
  return read_rows<JointRotationRow>(out, result_layout::kSmplJointRotationsCsv, result_layout::kJointRotationColumns,
                                     [&](const ResultCsv& csv, const std::vector<JointRotationRow>& rows) {
                                       JointRotationRow row;
                                       row.t_us = csv.time_after(0, previous, rows.empty());
                                       row.joint = joint_of(csv, body::kNumJoints, body::smpl_joint_names().data());
                                       row.K_from_joint = csv.quat(3);
                                       return row;
                                     });
}

std::vector<FitEnergyRow> read_fit_energies(Reading& out) {
  std::int64_t previous = 0;
  return read_rows<FitEnergyRow>(out, result_layout::kFitEnergyCsv, result_layout::kFitEnergyColumns,
                                 [&](const ResultCsv& csv, const std::vector<FitEnergyRow>& rows) {
                                   FitEnergyRow row;
                                   row.t_us = csv.time_after(0, previous, rows.empty());
                                   row.fit_energy = csv.number_or_nan(1);  // nan: a fit that failed
                                   return row;
                                 });
}

// Not in time order, even per arm: the forearm stage and, with `fit.enabled`, the body-fit stage
// both report each frame's forearms, the body fit up to `fit.imu_wait_s` later. Sorted by
// (arm, t_us) here, the rows of one frame kept in file order.
std::vector<ForearmRow> read_forearms(Reading& out) {
  std::vector<ForearmRow> rows = read_rows<ForearmRow>(out, result_layout::kForearmsCsv, result_layout::kForearmColumns,
                                                       [&](const ResultCsv& csv, const std::vector<ForearmRow>&) {
                                                         ForearmRow row;
                                                         row.arm = csv.arm(1);
                                                         row.t_us = csv.int64(0);
                                                         row.K_from_F = csv.quat(2);
                                                         row.pronation_rad = csv.number_or_nan(6);
                                                         row.source = csv.source(7);
                                                         row.confidence = csv.number(8);
                                                         return row;
                                                       });
  std::stable_sort(rows.begin(), rows.end(), [](const ForearmRow& a, const ForearmRow& b) {
    return std::make_pair(static_cast<int>(a.arm), a.t_us) < std::make_pair(static_cast<int>(b.arm), b.t_us);
  });
  return rows;
}

std::vector<ImuPositionRow> read_imu_positions(Reading& out) {
  std::map<std::string, std::int64_t> previous;  // per device
  return read_rows<ImuPositionRow>(out, result_layout::kImuPositionsCsv, result_layout::kImuPositionColumns,
                                   [&](const ResultCsv& csv, const std::vector<ImuPositionRow>&) {
                                     ImuPositionRow row;
                                     row.device_id = csv.device_id(1);
                                     const bool first = !previous.count(row.device_id);
                                     row.t_us = csv.time_after(0, previous[row.device_id], first);
                                     row.p_K = csv.vec3(2);
                                     row.source = csv.source(5);
                                     return row;
                                   });
}

std::vector<RecoveredRow> read_recovered(Reading& out) {
  std::int64_t previous = 0;
  return read_rows<RecoveredRow>(
      out, result_layout::kRecoveredSegmentsCsv, result_layout::kRecoveredSegmentColumns,
      [&](const ResultCsv& csv, const std::vector<RecoveredRow>& rows) {
        RecoveredRow row;
        row.device_id = csv.device_id(0);
        if (!v1::RecoveredSegment::Method_Parse(csv.text(1), &row.method) ||
            row.method == v1::RecoveredSegment::METHOD_UNSPECIFIED) {
          throw_invalid(csv.field(1), session::quoted(csv.text(1)) + " is not PAPER or SMOOTHER");
        }
        row.t_start_us = csv.int64(2);
        row.t_end_us = csv.int64(3);
        if (row.t_end_us < row.t_start_us) {
          throw_invalid(csv.field(3),
                        std::to_string(row.t_end_us) + " is before t_start_us " + std::to_string(row.t_start_us));
        }
        // Rows of one segment are consecutive; a new segment may start earlier than the last one.
        const bool same_segment = !rows.empty() && rows.back().device_id == row.device_id &&
                                  rows.back().method == row.method && rows.back().t_start_us == row.t_start_us &&
                                  rows.back().t_end_us == row.t_end_us;
        row.t_us = csv.time_after(4, previous, !same_segment);
        row.imu_K = csv.vec3(5);
        row.elbow_K = csv.vec3(8);
        row.wrist_K = csv.vec3(11);
        row.K_from_F = csv.quat(14);
        return row;
      });
}

std::vector<AngleRow> read_angles(Reading& out) {
  const std::vector<std::string> columns = result_layout::joint_angle_columns();
  const auto count = static_cast<std::size_t>(measures::kAngleCount);
  return read_rows<AngleRow>(out, result_layout::kJointAnglesCsv, columns, [&](ResultCsv& csv, const auto& rows) {
    AngleRow row;
    row.t_us = std::llround(csv.number(0) * 1e6);
    if (!rows.empty() && row.t_us <= rows.back().t_us) {
      throw_invalid(csv.field(0), "is not after the previous row's t_s");
    }
    for (std::size_t a = 0; a < count; ++a) {
      if (csv.text(1 + a).empty()) {
        row.deg.emplace_back();
      } else {
        row.deg.emplace_back(csv.number(1 + a));
      }
      row.confidence.push_back(csv.number(1 + count + a));
    }
    return row;
  });
}

std::vector<RepetitionRow> read_repetitions(Reading& out) {
  namespace layout = result_layout;
  // Earlier layouts, with fewer columns: before each repetition carried its confidence, and its
  // cut's ambiguity. Any other header is read as today's (and refused there if it is not).
  const bool present = has_entry(out.directory.get(), layout::kRepetitionsCsv, FileKind::kRegular);
  const auto written_as = [&](const std::vector<std::string>& columns) {
    return present && has_header(out.directory.get(), layout::kRepetitionsCsv, columns);
  };
  const bool with_confidence = !written_as(layout::kRepetitionColumnsWithoutConfidence);
  const bool with_cut = with_confidence && !written_as(layout::kRepetitionColumnsWithoutCutAmbiguity);
  const std::vector<std::string>& columns = with_cut          ? layout::kRepetitionColumns
                                            : with_confidence ? layout::kRepetitionColumnsWithoutCutAmbiguity
                                                              : layout::kRepetitionColumnsWithoutConfidence;
  return read_rows<RepetitionRow>(
      out, layout::kRepetitionsCsv, columns, [with_confidence, with_cut](ResultCsv& csv, const auto&) {
        RepetitionRow row;
        row.angle = csv.text(0);
        row.t_start_s = csv.number(2);
        row.t_peak_s = csv.number(3);
        row.t_end_s = csv.number(4);
        row.min_deg = csv.number(5);
        row.max_deg = csv.number(6);
        row.range_deg = csv.number(7);
        row.peak_speed_deg_s = csv.number(8);
        row.duration_s = csv.number(9);
        const std::string counted = csv.text(10);
        if (counted != "0" && counted != "1") throw_invalid(csv.field(10), "is not 0 or 1");
        row.counted = counted == "1";
        row.confidence = with_confidence ? csv.number(11) : std::numeric_limits<double>::quiet_NaN();
        if (with_confidence && !(row.confidence >= 0.0 && row.confidence <= 1.0))
          throw_invalid(csv.field(11), "is not a confidence in [0, 1]");
        row.cut_ambiguity_deg = with_cut ? csv.number(12) : std::numeric_limits<double>::quiet_NaN();
        if (with_cut && !(row.cut_ambiguity_deg >= 0.0)) throw_invalid(csv.field(12), "is not an angle >= 0");
        return row;
      });
}

}  // namespace

ResultDirectory read_result_files(const fs::path& directory) {
  if (!fs::is_directory(directory)) {
    throw Error(ErrorCode::kNotFound, directory.string(), "is not a directory of result files");
  }
  Reading in{open_path(directory, directory.string()), {}};
  require_directory(in.directory.get(), directory.string());
  ResultDirectory& out = in.result;
  out.directory = directory;
  out.imu_orientations = read_orientation_folder(in, result_layout::kImuOrientationDir, false);
  out.forearm_orientations = read_orientation_folder(in, result_layout::kForearmOrientationDir, true);
  out.offline_forearm_orientations = read_orientation_folder(in, result_layout::kForearmOrientationOfflineDir, true);
  out.smpl_joints = read_joints(in, result_layout::kSmplJointsCsv, body::kNumJoints, body::smpl_joint_names().data());
  out.smpl_joint_rotations = read_joint_rotations(in);
  out.fit_energies = read_fit_energies(in);
  out.camera_joints = read_joints(in, result_layout::kCameraJointsCsv,
                                  static_cast<int>(layout::kKinectJointNames.size()), layout::kKinectJointNames.data());
  out.forearms = read_forearms(in);
  out.imu_positions = read_imu_positions(in);
  out.recovered = read_recovered(in);
  out.joint_angles = read_angles(in);
  out.repetitions = read_repetitions(in);
  const char* calibration = result_layout::kCalibrationJson;
  if (has_entry(in.directory.get(), calibration, FileKind::kRegular)) {
    out.files.insert(calibration);
    const UniqueFd file = open_beneath(in.directory.get(), calibration, calibration);
    require_regular_file(file.get(), calibration);
    v1::CalibrationReport report;
    message_from_json(read_all(file.get(), calibration, kMaxJsonBytes), calibration, report);
    out.calibration = std::move(report);
  }
  return std::move(in.result);
}

}  // namespace posefuse::session
