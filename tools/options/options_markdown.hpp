#pragma once
// docs/options.md: every stage's SessionHeader.options from its option table, as Markdown.
#include <memory>
#include <string>
#include <vector>

#include "session/pipeline_stage.hpp"

namespace posefuse::tools {

// The command that writes docs/options.md, run from the repository root.
inline constexpr const char* kRegenerateOptionsDoc = "build/tools/options/posefuse-options-doc > docs/options.md";

std::string options_markdown(const std::vector<std::unique_ptr<session::Stage>>& stages);

}  // namespace posefuse::tools
