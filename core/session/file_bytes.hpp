#pragma once
// Whole-file reads and writes for single frames and small JSON files.
#include <filesystem>
#include <string>

namespace posefuse::session {

// kNotFound (field = `name`) when the file cannot be opened, kDataLoss when reading fails.
std::string read_file_bytes(const std::filesystem::path& path, const std::string& name);
// kFailedPrecondition when the file cannot be created, kDataLoss when writing fails.
void write_file_bytes(const std::filesystem::path& path, const std::string& bytes);

}  // namespace posefuse::session
