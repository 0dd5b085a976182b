#include "report/report_sections.hpp"

#include <cmath>
#include <limits>
#include <map>

#include "measures/joint_angles.hpp"
#include "report/html_text.hpp"
#include "session/frame_merge.hpp"

namespace posefuse::report {
namespace {

using measures::Angle;

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();
const char* const kPalette[] = {"#1f77b4", "#d62728", "#2ca02c", "#9467bd"};

double seconds(std::int64_t t_us) { return static_cast<double>(t_us) * 1e-6; }

PlotSeries angle_series(const session::ResultDirectory& results, Angle angle, const char* label, int colour) {
  PlotSeries s;
  s.label = label;
  s.colour = kPalette[colour];
  const auto a = static_cast<std::size_t>(angle);
  for (const session::AngleRow& row : results.joint_angles) {
    s.t_s.push_back(seconds(row.t_us));
    s.value.push_back(row.deg[a].value_or(kNaN));
    s.confidence.push_back(row.confidence[a]);
  }
  return s;
}

// Stretches of consecutive samples that `kind_of` gives a kind ("" = none), one Shade each.
template <typename Rows, typename KindOf>
std::vector<Shade> stretches(const Rows& rows, KindOf kind_of) {
  std::vector<Shade> out;
  bool open = false;
  for (const auto& row : rows) {
    const std::string kind = kind_of(row);
    if (kind.empty()) {
      open = false;
      continue;
    }
    if (open && out.back().kind == kind) {
      out.back().t1_s = seconds(row.t_us);
    } else {
      out.push_back({seconds(row.t_us), seconds(row.t_us), kind});
      open = true;
    }
  }
  return out;
}

std::vector<Shade> lost_fit(const session::ResultDirectory& results) {
  std::vector<session::JointRow> roots;
  for (const session::JointRow& row : results.smpl_joints)
    if (row.joint == 0) roots.push_back(row);
  return stretches(roots, [](const session::JointRow& row) {
    return row.confidence <= session::kLostFitConfidence ? std::string("lost") : std::string();
  });
}

std::vector<Shade> occluded(const session::ResultDirectory& results, v1::Arm arm) {
  std::vector<session::ImuPositionRow> rows;
  if (results.calibration) {
    for (const v1::ForearmModel& model : results.calibration->forearms()) {
      if (model.arm() != arm) continue;
      for (const session::ImuPositionRow& row : results.imu_positions)
        if (row.device_id == model.device_id()) rows.push_back(row);
    }
  }
  return stretches(rows, [](const session::ImuPositionRow& row) {
    if (row.source == v1::PREDICTED) return std::string("occluded");
    if (row.source == v1::RECOVERED) return std::string("recovered");
    return std::string();
  });
}

std::string row(const std::vector<std::string>& cells, const char* tag = "td") {
  std::string out = "<tr>";
  for (const std::string& cell : cells) out += std::string("<") + tag + ">" + cell + "</" + tag + ">";
  return out + "</tr>\n";
}

std::string cm(double m) { return fixed(100.0 * m, 1) + " cm"; }

}  // namespace

std::vector<PlotSpec> angle_plots(const session::ResultDirectory& results) {
  if (results.joint_angles.empty()) return {};
  const double t0 = seconds(results.joint_angles.front().t_us), t1 = seconds(results.joint_angles.back().t_us);
  const std::vector<Shade> lost = lost_fit(results);
  std::vector<PlotSpec> plots;
  PlotSpec thorax{"plot-thorax", "Thorax relative to vertical", t0, t1, {}, lost};
  thorax.series = {angle_series(results, Angle::kThoraxFlexion, "flexion", 0),
                   angle_series(results, Angle::kThoraxLateralTilt, "lateral tilt (right)", 1),
                   angle_series(results, Angle::kThoraxAxialRotation, "axial rotation (left)", 2)};
  plots.push_back(thorax);
  struct Side {
    const char* id;
    const char* name;
    v1::Arm arm;
    Angle plane, elevation, axial, elbow, pronation, girdle;
  };
  const Side sides[] = {
      {"left", "Left", v1::LEFT, Angle::kLeftPlaneOfElevation, Angle::kLeftElevation, Angle::kLeftHumerusAxialRotation,
       Angle::kLeftElbowFlexion, Angle::kLeftPronation, Angle::kLeftGirdleElevation},
      {"right", "Right", v1::RIGHT, Angle::kRightPlaneOfElevation, Angle::kRightElevation,
       Angle::kRightHumerusAxialRotation, Angle::kRightElbowFlexion, Angle::kRightPronation,
       Angle::kRightGirdleElevation},
  };
  for (const Side& side : sides) {
    std::vector<Shade> shades = lost;
    for (const Shade& s : occluded(results, side.arm)) shades.push_back(s);
    PlotSpec shoulder{std::string("plot-") + side.id + "-shoulder",
                      std::string(side.name) + " shoulder (humerothoracic)",
                      t0,
                      t1,
                      {},
                      shades};
    shoulder.series = {angle_series(results, side.elevation, "elevation", 0),
                       angle_series(results, side.plane, "plane of elevation", 1),
                       angle_series(results, side.axial, "axial rotation (internal)", 2),
                       angle_series(results, side.girdle, "girdle elevation", 3)};
    plots.push_back(shoulder);
    PlotSpec elbow{
        std::string("plot-") + side.id + "-elbow", std::string(side.name) + " elbow and forearm", t0, t1, {}, shades};
    elbow.series = {angle_series(results, side.elbow, "elbow flexion", 0),
                    angle_series(results, side.pronation, "pronation (+)", 1)};
    plots.push_back(elbow);
  }
  return plots;
}

std::string repetition_table(const session::ResultDirectory& results) {
  if (results.repetitions.empty())
    return "<p id=\"repetitions\" class=\"none\">No repetitions were found (they need the body fit and an angle that "
           "moves by the minimum amplitude, docs/measures.md).</p>\n";
  const double t0 = results.joint_angles.empty() ? 0.0 : seconds(results.joint_angles.front().t_us);
  std::string out = "<table id=\"repetitions\">\n";
  out += row({"#", "angle", "start (s)", "end (s)", "duration (s)", "min (deg)", "max (deg)", "range of motion (deg)",
              "peak speed (deg/s)", "confidence", ""},
             "th");
  std::map<std::string, std::vector<double>> ranges;
  int index = 0;
  for (const session::RepetitionRow& r : results.repetitions) {
    if (r.counted) ranges[r.angle].push_back(r.range_deg);
    // A range read off an extreme below kConfidentAt, or cut at a turn that may not end it, is
    // reported, and marked as not one to act on; the cut's doubt is named where it is one.
    const bool uncertain = r.confidence < measures::kConfidentAt;
    std::string note = !r.counted ? "partial, not counted" : uncertain ? "range not confident" : "";
    if (r.counted && uncertain && r.cut_ambiguity_deg > 0)
      note += ": cut at a turn near the middle of the range, up to " + fixed(r.cut_ambiguity_deg, 0) + " deg";
    out += "<tr class=\"" + std::string(r.counted ? "counted" : "partial") + (uncertain ? " uncertain" : "") +
           "\"><td>" + std::to_string(++index) + "</td><td>" + html_escape(r.angle) + "</td><td>" +
           fixed(r.t_start_s - t0, 2) + "</td><td>" + fixed(r.t_end_s - t0, 2) + "</td><td>" + fixed(r.duration_s, 2) +
           "</td><td>" + fixed(r.min_deg, 1) + "</td><td>" + fixed(r.max_deg, 1) + "</td><td>" + fixed(r.range_deg, 1) +
           "</td><td>" + fixed(r.peak_speed_deg_s, 0) + "</td><td>" + fixed(r.confidence, 2) + "</td><td>" + note +
           "</td></tr>\n";
  }
  out += "</table>\n<table id=\"repetition-summary\">\n";
  out += row({"angle", "repetitions counted", "mean range (deg)", "spread (SD, deg)"}, "th");
  for (const auto& [angle, values] : ranges) {
    double mean = 0.0, sd = 0.0;
    for (const double v : values) mean += v / static_cast<double>(values.size());
    for (const double v : values) sd += (v - mean) * (v - mean);
    sd = values.size() > 1 ? std::sqrt(sd / static_cast<double>(values.size() - 1)) : kNaN;
    out += row({html_escape(angle), std::to_string(values.size()), fixed(mean, 1), fixed(sd, 1)});
  }
  return out + "</table>\n";
}

std::string calibration_table(const session::ResultDirectory& results) {
  if (!results.calibration)
    return "<p id=\"calibration\" class=\"none\">No calibration report (calibration.json) in the results.</p>\n";
  const v1::CalibrationReport& c = *results.calibration;
  std::string out = "<table id=\"calibration\">\n";
  const v1::Quaternion& q = c.k_from_w();
  const bool world = q.w() * q.w() + q.x() * q.x() + q.y() * q.y() + q.z() * q.z() > 0.25;
  out += row(
      {"world alignment (K_from_W)",
       world ? "measured (base IMU)" : "not known: the thorax angles take the camera as level, at half confidence"});
  for (const v1::ForearmModel& m : c.forearms()) {
    const std::string arm = m.arm() == v1::LEFT ? "left" : m.arm() == v1::RIGHT ? "right" : "unknown";
    std::string text;
    if (!m.estimated()) {
      text = "not calibrated: no forearm orientation or pronation for this arm (warnings say why)";
    } else if (m.mounting_source() == v1::ForearmModel::MOTION) {
      text = "no calibration pose: IMU mounting estimated from " + std::to_string(m.mounting_frames()) +
             " frames of the session's motion, forearm orientation predicted within " +
             fixed(m.orientation_uncertainty_rad() * 180.0 / M_PI, 1) + " deg RMS (" + m.roll_limit() +
             "); no pronation relative to the calibration pose";
    } else {
      text = "calibration hold of " + std::to_string(m.calibration_frames()) + " frames, spread " +
             fixed(m.a_from_f_spread_rad() * 180.0 / M_PI, 1) + " deg; upper arm " + cm(m.d_ul_m()) +
             (m.d_ul_uncertainty_m() > 0.0 ? " (+/- " + cm(m.d_ul_uncertainty_m()) + ", the camera's joints)" : "") +
             ", strap to elbow " + cm(m.d_se_m()) + ", to wrist " + cm(m.d_sw_m()) + ", strap radius " + cm(m.r_m());
    }
    out += row({html_escape(arm + " forearm (" + m.device_id() + ")"), html_escape(text)});
  }
  for (const auto& [device, offset_us] : c.clock_offset_us()) {
    std::string text = fixed(static_cast<double>(offset_us) * 1e-3, 1) + " ms";
    if (const auto sigma = c.clock_offset_sigma_us().find(device); sigma != c.clock_offset_sigma_us().end())
      text += " &plusmn; " + fixed(sigma->second * 1e-3, 1) + " ms";
    if (const auto drift = c.clock_drift_ppm().find(device); drift != c.clock_drift_ppm().end())
      text += ", drift " + fixed(drift->second, 1) + " ppm";
    out += row({"clock offset " + html_escape(device), text});
  }
  const v1::BodyShape& b = c.body_shape();
  if (b.estimated()) {
    out += row({"body shape",
                "upper arm " + cm(b.upper_arm_length_left_m()) + " left, " + cm(b.upper_arm_length_right_m()) +
                    " right; forearm " + cm(b.forearm_length_left_m()) + " left, " + cm(b.forearm_length_right_m()) +
                    " right; shoulder width " + cm(b.shoulder_width_m()) + "; torso " + cm(b.torso_length_m())});
  } else {
    out +=
        row({"body shape", "not estimated: the body fit did not run, or fitted the template shape (warnings say why)"});
  }
  return out + "</table>\n";
}

std::string warning_list(const std::vector<std::string>& warning_lines) {
  if (warning_lines.empty()) return "<p id=\"warnings\" class=\"none\">No warnings.</p>\n";
  std::string out = "<ul id=\"warnings\">\n";
  for (const std::string& line : warning_lines) out += "<li>" + html_escape(line) + "</li>\n";
  return out + "</ul>\n";
}

}  // namespace posefuse::report
