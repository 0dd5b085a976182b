#include "tools/sim/sim_run.hpp"

#include <memory>

#include "common/error.hpp"
#include "session/chunk_file.hpp"
#include "session/directory_writer.hpp"
#include "sim/ground_truth_files.hpp"
#include "tools/sim/calibration_capture_files.hpp"
#include "tools/sim/contact_sheet.hpp"

namespace posefuse::tools {

SimRunResult run_simulation(const SimRunRequest& request,
                            const std::function<void(const sim::SimProgress&)>& progress) {
  if (request.out_directory.has_value() == request.chunk_file.has_value()) {
    throw Error(ErrorCode::kInvalidArgument, "--out/--chunk-file", "give exactly one of the two");
  }
  sim::validate(request.options);
  if (request.options.panel_capture.enabled) sim::validate(request.options.panel_capture);
  SimRunResult result;
  result.gt_directory = request.gt_directory    ? *request.gt_directory
                        : request.out_directory ? *request.out_directory / "gt"
                                                : std::filesystem::path(request.chunk_file->string() + ".gt");
  if (std::filesystem::exists(result.gt_directory) && !std::filesystem::is_empty(result.gt_directory)) {
    throw Error(ErrorCode::kFailedPrecondition, result.gt_directory.string(), "exists and is not empty");
  }
  std::unique_ptr<session::ChunkSink> sink;
  if (request.out_directory) {
    sink = std::make_unique<session::DirectoryWriter>(*request.out_directory);
  } else {
    sink = std::make_unique<session::ChunkFileWriter>(*request.chunk_file);
  }
  // The session's length first: the contact sheet shows the middle frame.
  sim::SimSessionOptions options = sim::with_session_duration(request.options);
  const auto middle_us = static_cast<std::int64_t>(0.5 * options.duration_s * 1e6);
  ContactSheetRecorder recorder(*sink, middle_us);
  session::ChunkSink& target = request.contact_sheet ? static_cast<session::ChunkSink&>(recorder) : *sink;
  // A directory stores depth as PNG: encoding it so on the frame threads spares the writer
  // (this thread) decoding zstd and encoding PNG per frame; the files are the same.
  if (request.out_directory) options.depth_encoding = v1::DepthFrame::PNG16;
  const sim::SimTruth truth = sim::simulate_session(options, target, progress);
  target.finish();
  sim::write_ground_truth(truth, result.gt_directory);
  if (request.contact_sheet) write_png(recorder.render(), *request.contact_sheet);
  if (request.options.panel_capture.enabled) {
    // The same rig: camera, room, base IMU mounting, earth field and IMU model.
    sim::PanelCaptureRig rig;
    rig.depth_intrinsics = request.options.depth_intrinsics;
    rig.K_from_W = truth.K_from_W;
    rig.K_from_B = truth.K_from_B;
    rig.camera_height_m = request.options.camera_height_m;
    rig.wall_distance_m = request.options.wall_distance_m;
    rig.depth_noise = request.options.depth_noise;
    rig.imu_rate_hz = request.options.imu.rate_hz;
    rig.imu = request.options.imu.synth;
    rig.seed = request.options.seed;
    result.calibration_capture = request.out_directory
                                     ? *request.out_directory / "calibration_capture"
                                     : std::filesystem::path(request.chunk_file->string() + ".calibration_capture");
    write_calibration_capture(sim::simulate_panel_capture(request.options.panel_capture, rig),
                              *result.calibration_capture);
  }
  result.chunks = truth.chunks;
  result.warnings = truth.warnings;
  result.duration_s = truth.options.duration_s;
  result.frames = static_cast<std::int64_t>(truth.frames.size());
  return result;
}

}  // namespace posefuse::tools
