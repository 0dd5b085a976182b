#pragma once
// Per recovered gap of one arm, against the simulator's truth (bench_table1 --gaps): why a
// recovery is off. Gap length; the 500 ms boundary line fits (II-K.1, forearm::fit_boundary_line
// over the stage's VISUAL track) at entry and exit, their position and velocity errors; the
// worst VISUAL sample inside those windows (a false strap detection pulls the fit); and each
// method's error at the gap's ends and its peak (value, time into the gap).
#include <vector>

#include "posefuse/v1/results.pb.h"
#include "table1_errors.hpp"

namespace posefuse::bench {

void print_gap_report(const Table1Truth& truth, const std::vector<v1::FitResult>& results, const Table1Arm& arm);

}  // namespace posefuse::bench
