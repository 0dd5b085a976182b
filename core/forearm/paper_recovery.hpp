#pragma once
// Paper 1's gap recovery, faithfully (II-K, II-L): boundary lines over 500 ms, double
// integration of net acceleration with linear velocity and position drift corrections, then a
// radial snap of every position onto the shoulder sphere.
#include "forearm/gap_input.hpp"

namespace posefuse::forearm {

struct PaperRecoveryOptions {
  double boundary_window_s = 0.5;     // II-K.1
  bool apply_shoulder_sphere = true;  // II-L.3
};

// Recovers `gap` (from find_gaps(input.track)) at its boundary times and every arm sample in
// between. Throws posefuse::Error: whatever validate(input) throws; kFailedPrecondition
// "track.before_gap" / "track.after_gap" when the gap lacks boundary data, "arm" when the arm or
// shoulder series do not cover the gap.
RecoveredGap recover_gap_paper(const GapRecoveryInput& input, const GapSpan& gap,
                               const PaperRecoveryOptions& options = {});

}  // namespace posefuse::forearm
