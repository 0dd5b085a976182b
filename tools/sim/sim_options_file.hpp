#pragma once
// posefuse-sim's options file: plain text, one `key = value` per line, `#` starts a comment,
// blank lines ignored, each key at most once. Every key and value is checked; an error names
// the file, line and key and quotes the value (posefuse::Error, kInvalidArgument).
// The keys are listed in sim_option_keys() and documented in docs/simulator.md.
#include <filesystem>
#include <string>
#include <vector>

#include "sim/sim_session.hpp"

namespace posefuse::tools {

struct SimOptionKey {
  const char* key;
  const char* meaning;
};
const std::vector<SimOptionKey>& sim_option_keys();

// Applies `text` (the content of a file called `name` in errors) onto `options`.
void apply_sim_options(const std::string& text, const std::string& name, sim::SimSessionOptions& options);
void apply_sim_options_file(const std::filesystem::path& path, sim::SimSessionOptions& options);

// One `key = value` setting (also used for command-line flags); `field` names it in errors.
void apply_sim_option(const std::string& key, const std::string& value, const std::string& field,
                      sim::SimSessionOptions& options);

}  // namespace posefuse::tools
