#pragma once
// `posefuse export`: one OpenSim file, or the glTF body, from a result directory (docs/exports.md).
#include <filesystem>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

namespace posefuse::opensim {

enum class ExportFormat { kTrc, kMot, kSto, kGltf };

// "trc", "mot", "sto", "gltf"; nullopt for anything else.
std::optional<ExportFormat> export_format(std::string_view name);
// The file written into the result directory when no output is named: markers.trc,
// joint_angles.mot, imu_orientations.sto, body.glb (binary glTF: one self-contained file).
std::string default_export_name(ExportFormat format);

struct ExportReport {
  std::filesystem::path file;
  std::string summary;                // one line: what was written
  std::vector<std::string> warnings;  // what the file cannot say (an assumed vertical, missing values)
};

// Reads `results_dir` (session::read_result_files) and writes `out_file` (empty: the default
// name inside results_dir) through a temporary file beside it, so that a failure leaves no
// partial file. Throws posefuse::Error: the reader's, the writers' (kFailedPrecondition naming
// the missing results) and kNotFound "out" when the file cannot be written.
ExportReport export_results(const std::filesystem::path& results_dir, ExportFormat format,
                            const std::filesystem::path& out_file = {});

}  // namespace posefuse::opensim
