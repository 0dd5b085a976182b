#pragma once
// The minimum stream rate of a Fit session (docs/server.md, "Limits").
//
// A live session streams a recording at least as fast as it was recorded, and an upload of a
// finished recording goes far faster; a client whose data advances much slower than wall time
// holds one of the max_sessions slots without being either. So once the grace period is over,
// the stream time the session has delivered (SessionValidator::stream_time_us) must be at least
// min_rate times the wall time it had to deliver it. The wall time counted is the time the
// session waited for its client (the caller leaves out the time the server itself was busy with
// the session's chunks), so a slow or overloaded server never makes a fast client fall behind.
#include <optional>
#include <string>

namespace posefuse::server {

struct StreamRateRule {
  double min_rate = 0.5;  // stream seconds per wall second; 0 disables the rule
  double grace_s = 60.0;  // wall seconds before the rule applies
};

// How far a session fell behind.
struct StreamRateShortfall {
  double wall_s = 0.0;    // wall time counted
  double stream_s = 0.0;  // stream time delivered in it
  double rate = 0.0;      // stream_s / wall_s
  double required_rate = 0.0;
};

// Nothing while the session keeps up, is within its grace period or the rule is off; else the
// shortfall. A negative or non-finite stream time counts as none (no progress can be faked with
// it); a non-finite or negative wall time is never judged.
std::optional<StreamRateShortfall> stream_rate_shortfall(const StreamRateRule& rule, double wall_s, double stream_s);

// One sentence for the status message, naming the measured and the required rate and the
// server options that set the rule.
std::string describe(const StreamRateShortfall& shortfall, const StreamRateRule& rule);

}  // namespace posefuse::server
