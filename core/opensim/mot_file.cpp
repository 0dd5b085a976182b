#include "opensim/mot_file.hpp"

#include "common/error.hpp"
#include "measures/joint_angles.hpp"
#include "session/text_fields.hpp"

namespace posefuse::opensim {

MotSummary write_mot(const session::ResultDirectory& results, const std::string& name, std::ostream& out) {
  if (results.joint_angles.empty())
    throw_precondition("joint_angles.csv", "the results have no joint angles (they need the body fit, fit.enabled)");
  MotSummary summary;
  summary.rows = results.joint_angles.size();
  summary.columns = measures::kAngleCount;
  out << name << "\nversion=1\nnRows=" << summary.rows << "\nnColumns=" << summary.columns + 1
      << "\ninDegrees=yes\nendheader\ntime";
  for (int a = 0; a < measures::kAngleCount; ++a) out << '\t' << measures::angle_name(static_cast<measures::Angle>(a));
  out << '\n';
  for (const session::AngleRow& row : results.joint_angles) {
    out << session::format_seconds(row.t_us);
    for (std::size_t a = 0; a < summary.columns; ++a) {
      const bool usable = row.deg[a].has_value() && row.confidence[a] > 0.0;
      if (!usable) ++summary.missing;
      out << '\t' << (usable ? session::format_double(*row.deg[a]) : std::string("NaN"));
    }
    out << '\n';
  }
  return summary;
}

}  // namespace posefuse::opensim
