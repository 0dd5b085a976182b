#pragma once
// Header options that look like a stage's but that no stage declares. SessionHeader.options also
// carries metadata ("sim.seed", "demo.generator"), so only keys under a stage's prefix ("fit.",
// "imu.", the part before the first '.' of a declared key) count: such a key is most likely a
// misspelt option, which would otherwise leave the default in force without a word.
#include <string>
#include <vector>

#include "posefuse/v1/session.pb.h"
#include "session/option_table.hpp"

namespace posefuse::session {

struct UnknownOption {
  std::string key;
  std::string closest;  // the declared key nearest in spelling, or empty when none is near
};

// In the header's key order (sorted, for a deterministic report).
std::vector<UnknownOption> unknown_stage_options(const v1::SessionHeader& header,
                                                 const std::vector<const OptionTable*>& tables);

}  // namespace posefuse::session
