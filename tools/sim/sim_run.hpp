#pragma once
// What `posefuse-sim` does, as a function the tests call: simulate one session, write it as a
// recording directory (with gt/ inside) or as a chunk file (with gt/ beside it), optionally a
// contact sheet, and the calibration-panel capture (calibration_capture_files.hpp) when asked.
#include <filesystem>
#include <functional>
#include <optional>
#include <string>
#include <vector>

#include "sim/sim_session.hpp"

namespace posefuse::tools {

struct SimRunRequest {
  sim::SimSessionOptions options;
  std::optional<std::filesystem::path> out_directory;  // exactly one of these two
  std::optional<std::filesystem::path> chunk_file;
  std::optional<std::filesystem::path> gt_directory;   // default: <out>/gt or <chunk_file>.gt
  std::optional<std::filesystem::path> contact_sheet;  // PNG
};

struct SimRunResult {
  std::filesystem::path gt_directory;
  std::uint64_t chunks = 0;
  std::int64_t frames = 0;
  double duration_s = 0;              // the session's length (the clip's with duration_s = clip)
  std::vector<std::string> warnings;  // input repaired on the way, one line each
  // options.panel_capture.enabled: <out>/calibration_capture or <chunk_file>.calibration_capture
  std::optional<std::filesystem::path> calibration_capture;
};

// kInvalidArgument for a request without (or with both) outputs; errors of the simulator and
// the writers pass through.
SimRunResult run_simulation(const SimRunRequest& request,
                            const std::function<void(const sim::SimProgress&)>& progress = {});

}  // namespace posefuse::tools
