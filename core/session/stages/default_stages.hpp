#pragma once
// The stages every session runs through, in order. Forearm recovery and body fitting are added
// here when they land; callers (server, tests) do not change.
#include <memory>
#include <vector>

#include "session/pipeline_stage.hpp"

namespace posefuse::session {

std::vector<std::unique_ptr<Stage>> make_default_stages();

}  // namespace posefuse::session
