#pragma once
// The parts of the session report (docs/report.md), each from a result directory: the angle
// plots with their shaded stretches, the repetition table, the calibration summary, warnings.
#include <string>
#include <vector>

#include "report/svg_plot.hpp"
#include "session/result_reader.hpp"

namespace posefuse::report {

// Five plots: the thorax, then per side the shoulder (plane of elevation, elevation, axial
// rotation, girdle elevation) and the elbow and forearm (flexion, pronation). Arm plots shade the
// arm's occluded stretches (its IMU position not seen: PREDICTED, or RECOVERED after the gap);
// every plot shades the frames where the body fit lost tracking. Empty without joint angles.
std::vector<PlotSpec> angle_plots(const session::ResultDirectory& results);

// <table id="repetitions">: one row per repetition (partial ones marked), and the session's
// count, mean and spread of the range of motion per angle.
std::string repetition_table(const session::ResultDirectory& results);

// <table id="calibration">: the world alignment, each arm's forearm model and calibration hold,
// clock offsets, the body shape.
std::string calibration_table(const session::ResultDirectory& results);

// <ul id="warnings"> of warnings.txt's lines (the client's), or a line saying there were none.
std::string warning_list(const std::vector<std::string>& warning_lines);

}  // namespace posefuse::report
