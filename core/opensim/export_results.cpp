#include "opensim/export_results.hpp"

#include <fstream>
#include <system_error>

#include "common/error.hpp"
#include "gltf/body_animation.hpp"
#include "gltf/fitted_shape.hpp"
#include "gltf/gltf_body_file.hpp"
#include "gltf/skinned_mesh.hpp"
#include "opensim/ground_frame.hpp"
#include "opensim/mot_file.hpp"
#include "opensim/sto_file.hpp"
#include "opensim/trc_file.hpp"

namespace posefuse::opensim {
namespace {

const char* const kAssumedVertical =
    "calibration.json has no K_from_W (no calibrated arm IMU): the ground's y is the camera's y, which holds only "
    "for a level camera";

std::string write_gltf(const session::ResultDirectory& results, const GroundFrame& ground, std::ostream& out,
                       std::vector<std::string>& warnings) {
  const gltf::BodyAnimation animation = gltf::body_animation(results);
  const gltf::FittedShape shape = gltf::fitted_shape(results);
  warnings.insert(warnings.end(), shape.warnings.begin(), shape.warnings.end());
  if (!ground.vertical_measured) warnings.push_back(kAssumedVertical);
  if (animation.incomplete_frames > 0)
    warnings.push_back(std::to_string(animation.incomplete_frames) +
                       " fitted frames left out: not all 24 joint rotations, or no pelvis position");
  const gltf::SkinnedMesh mesh = gltf::skinned_mesh(*shape.model, shape.beta);
  if (mesh.dropped_influences > 0)
    warnings.push_back(std::to_string(mesh.dropped_influences) +
                       " vertices have more than 4 skinning joints: the smallest weights were dropped");
  Eigen::Isometry3d gltf_from_K = Eigen::Isometry3d::Identity();
  gltf_from_K.linear() = gltf::gltf_from_ground() * ground.G_from_K;
  gltf_from_K.translation() = -gltf_from_K.linear() * ground.origin_K;
  const gltf::GltfSummary s = gltf::write_gltf_body(mesh, animation, gltf_from_K, out);
  return std::to_string(s.frames) + " frames of 24 joints animating a mesh of " + std::to_string(s.vertices) +
         " vertices";
}

std::string write_file(const session::ResultDirectory& results, ExportFormat format, const std::string& file_name,
                       std::ostream& out, std::vector<std::string>& warnings) {
  const GroundFrame ground = ground_frame(results);
  switch (format) {
    case ExportFormat::kTrc: {
      const TrcSummary s = write_trc(results, ground, file_name, out);
      if (!ground.vertical_measured) warnings.push_back(kAssumedVertical);
      if (s.missing > 0)
        warnings.push_back(std::to_string(s.missing) +
                           " marker samples are NaN (joints absent or lost by the body fit)");
      return std::to_string(s.frames) + " frames of " + std::to_string(s.markers) + " markers at " +
             std::to_string(static_cast<int>(std::lround(s.rate_hz))) + " Hz";
    }
    case ExportFormat::kMot: {
      const MotSummary s = write_mot(results, file_name, out);
      if (s.missing > 0)
        warnings.push_back(std::to_string(s.missing) + " angle values are NaN (undefined, or held at confidence 0)");
      return std::to_string(s.rows) + " frames of " + std::to_string(s.columns) + " joint angles";
    }
    case ExportFormat::kSto: {
      const StoSummary s = write_sto(results, ground, out);
      if (!s.camera_ground)
        warnings.push_back(
            "calibration.json has no K_from_W: orientations are in the world frame turned y up "
            "(x north), not in the markers' ground");
      if (!s.camera_clock)
        warnings.push_back("calibration.json lacks a clock offset for some IMU: times are the IMUs' device clocks");
      return std::to_string(s.rows) + " rows of " + std::to_string(s.imus) + " IMU orientations at " +
             std::to_string(static_cast<int>(std::lround(s.rate_hz))) + " Hz";
    }
    case ExportFormat::kGltf: return write_gltf(results, ground, out, warnings);
  }
  throw Error(ErrorCode::kInternal, "format", "unknown export format");
}

}  // namespace

std::optional<ExportFormat> export_format(std::string_view name) {
  if (name == "trc") return ExportFormat::kTrc;
  if (name == "mot") return ExportFormat::kMot;
  if (name == "sto") return ExportFormat::kSto;
  if (name == "gltf") return ExportFormat::kGltf;
  return std::nullopt;
}

std::string default_export_name(ExportFormat format) {
  switch (format) {
    case ExportFormat::kTrc: return "markers.trc";
    case ExportFormat::kMot: return "joint_angles.mot";
    case ExportFormat::kSto: return "imu_orientations.sto";
    case ExportFormat::kGltf: return "body.glb";
  }
  return "export";
}

ExportReport export_results(const std::filesystem::path& results_dir, ExportFormat format,
                            const std::filesystem::path& out_file) {
  const session::ResultDirectory results = session::read_result_files(results_dir);
  ExportReport report;
  report.file = out_file.empty() ? results_dir / default_export_name(format) : out_file;
  const std::filesystem::path partial = report.file.string() + ".partial";
  {
    std::ofstream out(partial, std::ios::binary | std::ios::trunc);
    if (!out) throw Error(ErrorCode::kNotFound, "out", "cannot write " + partial.string());
    try {
      report.summary = write_file(results, format, report.file.filename().string(), out, report.warnings);
    } catch (...) {
      out.close();
      std::error_code ignored;
      std::filesystem::remove(partial, ignored);
      throw;
    }
    out.close();
    if (!out) throw Error(ErrorCode::kNotFound, "out", "writing " + partial.string() + " failed");
  }
  std::filesystem::rename(partial, report.file);
  return report;
}

}  // namespace posefuse::opensim
