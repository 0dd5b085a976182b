#pragma once
// Folders for tests that write files: one scratch root per test program and process under the
// system's temp directory, removed with everything in it when the process exits (each CTest
// test is its own process), so repeated runs do not pile up folders in /tmp.
#include <unistd.h>

#include <filesystem>
#include <map>
#include <string>
#include <system_error>

namespace posefuse::testing {

// `<temp>/<program>_<pid>/<name>`, emptied; its parent exists, the folder itself does not.
inline std::filesystem::path fresh_scratch_dir(const std::string& program, const std::string& name) {
  // Removes the roots handed out when the process exits.
  struct Roots {
    std::map<std::string, std::filesystem::path> by_program;
    ~Roots() {
      for (const auto& [program, root] : by_program) {
        std::error_code ignored;
        std::filesystem::remove_all(root, ignored);
      }
    }
  };
  static Roots roots;
  auto [it, inserted] = roots.by_program.try_emplace(program);
  if (inserted) it->second = std::filesystem::temp_directory_path() / (program + "_" + std::to_string(::getpid()));
  const std::filesystem::path dir = it->second / name;
  std::filesystem::remove_all(dir);
  std::filesystem::create_directories(it->second);
  return dir;
}

}  // namespace posefuse::testing
