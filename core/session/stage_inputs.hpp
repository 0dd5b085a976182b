#pragma once
// How the pipeline hands a stage its inputs, and a whole recorded session assembled as the
// pipeline assembles it, for the benchmarks and tests that drive one stage object themselves
// (its per-frame statistics, truth values in place of an earlier stage's).
#include <vector>

#include "session/frame_assembler.hpp"
#include "session/pipeline_stage.hpp"

namespace posefuse::session {

// Calls the stage's method for the input's kind.
void deliver_input(Stage& stage, const SessionInput& input, StageOutput& out);

struct AssembledSession {
  v1::SessionHeader header;
  std::vector<SessionInput> inputs;  // in the order the pipeline hands them on
  std::vector<AssemblyWarning> warnings;
};
// Validates `chunks` (header first, end marker optional) and assembles them. Throws
// posefuse::Error for the first chunk the validator or the assembler refuses.
AssembledSession assemble_session(const std::vector<v1::SessionChunk>& chunks);

}  // namespace posefuse::session
