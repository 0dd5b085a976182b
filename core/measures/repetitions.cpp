#include "measures/repetitions.hpp"
#include "common/percentile.hpp"

#include <algorithm>
#include <charconv>
#include <cmath>
#include <cstddef>
#include <limits>
#include <numbers>
#include <optional>
#include <string>
#include <system_error>
#include <vector>

#include "common/error.hpp"
#include "forearm/orientation_uncertainty.hpp"
#include "measures/joint_angles.hpp"

namespace posefuse::measures {
namespace {

// The shortest text that reads back as the same double, so that a message quotes the offending
// value as the caller wrote it ("3.1", not "3.100000").
std::string text(double value) {
  char buffer[64];
  const auto [end, error] = std::to_chars(buffer, buffer + sizeof buffer, value);
  return error == std::errc{} ? std::string(buffer, end) : std::string("(unprintable)");
}

std::string element(const char* name, std::size_t i, double value) {
  return std::string(name) + "[" + std::to_string(i) + "] = " + text(value);
}

void check_series(const std::vector<double>& t_s, const std::vector<double>& angle_deg) {
  if (angle_deg.size() != t_s.size()) {
    throw_invalid("angle_deg", "has " + std::to_string(angle_deg.size()) + " samples but t_s has " +
                                   std::to_string(t_s.size()) + "; they must pair up one to one");
  }
  for (std::size_t i = 0; i < t_s.size(); ++i) {
    if (!std::isfinite(t_s[i])) throw_invalid("t_s", element("t_s", i, t_s[i]) + " is not a finite time");
    // `!(a > b)` rather than `a <= b`: the same test, and it reads as the rule it enforces.
    if (i > 0 && !(t_s[i] > t_s[i - 1])) {
      throw_invalid("t_s", element("t_s", i, t_s[i]) + " is not after " + element("t_s", i - 1, t_s[i - 1]));
    }
    if (std::isinf(angle_deg[i])) {
      throw_invalid("angle_deg",
                    element("angle_deg", i, angle_deg[i]) + " is infinite (a missing sample is marked with NaN)");
    }
  }
}

// `confidence` pairs up with `paired` (named `paired_name`) sample by sample, or is empty.
void check_confidence(const std::vector<float>& confidence, const std::vector<double>& paired,
                      const std::string& paired_name) {
  if (confidence.empty()) return;
  if (confidence.size() != paired.size()) {
    throw_invalid("confidence", "has " + std::to_string(confidence.size()) + " samples but " + paired_name + " has " +
                                    std::to_string(paired.size()) + "; give one per sample or none");
  }
  for (std::size_t i = 0; i < confidence.size(); ++i) {
    if (!(confidence[i] >= 0.0f && confidence[i] <= 1.0f))
      throw_invalid("confidence", element("confidence", i, confidence[i]) + " is not in [0, 1]");
  }
}

void check_options(const RepetitionOptions& options) {
  const std::string prefix = "repetition_options.";
  if (!(std::isfinite(options.hysteresis_deg) && options.hysteresis_deg > 0)) {
    throw_invalid(prefix + "hysteresis_deg",
                  "hysteresis_deg = " + text(options.hysteresis_deg) + " is not a positive, finite angle");
  }
  // A swing smaller than the hysteresis never makes a turning point, so such a bound would be
  // meaningless rather than lenient.
  if (!(std::isfinite(options.min_amplitude_deg) && options.min_amplitude_deg >= options.hysteresis_deg)) {
    throw_invalid(prefix + "min_amplitude_deg",
                  "min_amplitude_deg = " + text(options.min_amplitude_deg) +
                      " is not a finite angle of at least hysteresis_deg = " + text(options.hysteresis_deg));
  }
  if (!(std::isfinite(options.min_duration_s) && options.min_duration_s >= 0)) {
    throw_invalid(prefix + "min_duration_s",
                  "min_duration_s = " + text(options.min_duration_s) + " is not a finite, non-negative duration");
  }
  // Infinite is allowed: no upper bound.
  if (!(options.max_duration_s >= options.min_duration_s)) {
    throw_invalid(prefix + "max_duration_s", "max_duration_s = " + text(options.max_duration_s) +
                                                 " is not at least min_duration_s = " + text(options.min_duration_s));
  }
  // Infinite is allowed: never cut.
  if (!(options.max_gap_s >= 0)) {
    throw_invalid(prefix + "max_gap_s", "max_gap_s = " + text(options.max_gap_s) + " is not a non-negative duration");
  }
}

// A stretch of the series with no cut in it: the indices of its finite samples, in time order.
using Piece = std::vector<std::size_t>;

// Missing samples are skipped; wherever two consecutive finite samples are more than `max_gap_s`
// apart (a NaN stretch, or a jump in the timestamps) the series is cut, because what the angle did
// in between is unknown.
std::vector<Piece> split_at_gaps(const std::vector<double>& t_s, const std::vector<double>& angle_deg,
                                 double max_gap_s) {
  std::vector<Piece> pieces;
  Piece current;
  for (std::size_t i = 0; i < t_s.size(); ++i) {
    if (std::isnan(angle_deg[i])) continue;
    if (!current.empty() && t_s[i] - t_s[current.back()] > max_gap_s) {
      pieces.push_back(current);
      current.clear();
    }
    current.push_back(i);
  }
  if (!current.empty()) pieces.push_back(current);
  return pieces;
}

// Positions in `piece` (not indices in the series) of its troughs, found with hysteresis. Only
// troughs are returned: each repetition runs from one trough to the next, and its peak is simply
// its highest sample.
std::vector<std::size_t> find_troughs(const Piece& piece, const std::vector<double>& angle_deg, double hysteresis_deg) {
  const auto angle = [&](std::size_t position) { return angle_deg[piece[position]]; };
  enum class Heading { kUnknown, kRising, kFalling };
  Heading heading = Heading::kUnknown;
  std::size_t low = 0, high = 0;  // the running minimum and maximum since the last turn
  std::vector<std::size_t> troughs;
  for (std::size_t p = 1; p < piece.size(); ++p) {
    const double value = angle(p);
    switch (heading) {
      case Heading::kUnknown:
        // Before the first turn either end may come first; whichever reversal reaches the
        // hysteresis first decides.
        if (value < angle(low)) low = p;
        if (value > angle(high)) high = p;
        if (value - angle(low) >= hysteresis_deg) {
          troughs.push_back(low);
          heading = Heading::kRising;
          high = p;
        } else if (angle(high) - value >= hysteresis_deg) {
          heading = Heading::kFalling;
          low = p;
        }
        break;
      case Heading::kRising:
        if (value > angle(high)) {
          high = p;
        } else if (angle(high) - value >= hysteresis_deg) {
          heading = Heading::kFalling;  // the peak at `high` is confirmed
          low = p;
        }
        break;
      case Heading::kFalling:
        if (value < angle(low)) {
          low = p;
        } else if (value - angle(low) >= hysteresis_deg) {
          troughs.push_back(low);
          heading = Heading::kRising;
          high = p;
        }
        break;
    }
  }
  // A recording usually stops at rest, where nothing rises again to confirm the last trough. A
  // final descent that has come back to within the hysteresis of the trough its cycle started
  // from has ended that cycle, so its lowest point is taken as a trough; one that has not is a
  // repetition cut by the end of the piece.
  if (heading == Heading::kFalling && !troughs.empty() && angle(low) <= angle(troughs.back()) + hysteresis_deg) {
    troughs.push_back(low);
  }
  return troughs;
}

// |d angle / dt| at each position of `piece`: central differences over the neighbouring finite
// samples (across a bridged gap too), one-sided at the ends of the piece, 0 for a lone sample.
std::vector<double> speeds(const Piece& piece, const std::vector<double>& t_s, const std::vector<double>& angle_deg) {
  std::vector<double> result(piece.size(), 0.0);
  if (piece.size() < 2) return result;
  for (std::size_t p = 0; p < piece.size(); ++p) {
    const std::size_t before = piece[p == 0 ? p : p - 1];
    const std::size_t after = piece[p + 1 == piece.size() ? p : p + 1];
    result[p] = std::abs((angle_deg[after] - angle_deg[before]) / (t_s[after] - t_s[before]));
  }
  return result;
}

// The repetition spanning positions [first, last] of `piece`, not yet judged.
Repetition describe(const Piece& piece, const std::vector<double>& t_s, const std::vector<double>& angle_deg,
                    const std::vector<double>& piece_speeds, std::size_t first, std::size_t last) {
  Repetition rep;
  rep.t_start_s = t_s[piece[first]];
  rep.t_end_s = t_s[piece[last]];
  rep.duration_s = rep.t_end_s - rep.t_start_s;
  rep.min_deg = rep.max_deg = angle_deg[piece[first]];
  rep.t_peak_s = rep.t_start_s;
  for (std::size_t p = first; p <= last; ++p) {
    const double value = angle_deg[piece[p]];
    rep.min_deg = std::min(rep.min_deg, value);
    if (value > rep.max_deg) {
      rep.max_deg = value;
      rep.t_peak_s = t_s[piece[p]];
    }
    rep.peak_speed_deg_s = std::max(rep.peak_speed_deg_s, piece_speeds[p]);
  }
  rep.range_deg = rep.max_deg - rep.min_deg;
  return rep;
}

// Whether a trough -> peak -> trough cycle is a complete repetition: both swings large enough and
// a plausible duration.
bool duration_within_bounds(const Repetition& rep, const RepetitionOptions& options) {
  return rep.duration_s >= options.min_duration_s && rep.duration_s <= options.max_duration_s;
}

bool is_complete(const Repetition& cycle, double start_deg, double end_deg, const RepetitionOptions& options) {
  const bool rise_ok = cycle.max_deg - start_deg >= options.min_amplitude_deg;
  const bool fall_ok = cycle.max_deg - end_deg >= options.min_amplitude_deg;
  return rise_ok && fall_ok && duration_within_bounds(cycle, options);
}

// The range of positions [first, last] of `piece`, and the position of its highest sample (the
// first of equals).
struct PieceRange {
  double range_deg = 0;
  std::size_t peak = 0;
};
PieceRange range_over(const Piece& piece, const std::vector<double>& angle_deg, std::size_t first, std::size_t last) {
  double low = angle_deg[piece[first]];
  PieceRange out{0.0, first};
  for (std::size_t p = first; p <= last; ++p) {
    const double value = angle_deg[piece[p]];
    low = std::min(low, value);
    if (value > angle_deg[piece[out.peak]]) out.peak = p;
  }
  out.range_deg = angle_deg[piece[out.peak]] - low;
  return out;
}

// How much the range of the repetition between bounds[k] and bounds[k + 1] would change were the
// turns near the middle of the range read the other way: bounding turns near it (bound_near) not
// ending repetitions, so that this one runs on past them to the nearest bound that is not, and
// turns near it inside (inner_near) ending them, which leaves the repetition the part that holds
// its peak. Either reading is as likely as the other, so the change is the range's error bound.
// The piece's ends (bounds' first and last) are never near.
double cut_ambiguity_deg(const Piece& piece, const std::vector<double>& angle_deg,
                         const std::vector<std::size_t>& bounds, const std::vector<bool>& bound_near,
                         const std::vector<std::size_t>& inner_near, std::size_t k) {
  const PieceRange own = range_over(piece, angle_deg, bounds[k], bounds[k + 1]);
  std::size_t first_bound = k, last_bound = k + 1;
  while (bound_near[first_bound]) --first_bound;
  while (bound_near[last_bound]) ++last_bound;
  std::size_t split_first = bounds[k], split_last = bounds[k + 1];
  for (const std::size_t turn : inner_near) {
    if (turn > split_first && turn <= own.peak) split_first = turn;
    if (turn < split_last && turn >= own.peak) split_last = turn;
  }
  const double merged = range_over(piece, angle_deg, bounds[first_bound], bounds[last_bound]).range_deg;
  const double split = range_over(piece, angle_deg, split_first, split_last).range_deg;
  return std::max(merged - own.range_deg, own.range_deg - split);
}

// Appends the repetitions of one piece: the cycles between its troughs, and, as partial ones,
// the motion before its first trough and after its last, when that motion is a real reversal
// (at least the hysteresis) rather than noise.
// Only troughs in the resting half of the motion (at most `rest_limit_deg`) bound repetitions:
// a dip while the limb is held away from rest (a wobble at the top of a raise) is part of the
// repetition, not the end of one. The times of troughs within the hysteresis of that bound, on
// either side, go to `troughs_near_middle_t_s`, and each repetition they bound or lie in gets its
// cut_ambiguity_deg.
void add_piece(const Piece& piece, const std::vector<double>& t_s, const std::vector<double>& angle_deg,
               const RepetitionOptions& options, double rest_limit_deg, std::vector<Repetition>& out,
               std::vector<double>& troughs_near_middle_t_s) {
  // The repetitions run between consecutive bounds: the piece's ends and the troughs in between.
  const std::size_t end = piece.size() - 1;
  std::vector<std::size_t> bounds{0}, inner_near;
  std::vector<bool> bound_near{false};
  for (const std::size_t trough : find_troughs(piece, angle_deg, options.hysteresis_deg)) {
    const double value = angle_deg[piece[trough]];
    const bool near = std::abs(value - rest_limit_deg) < options.hysteresis_deg;
    if (near) troughs_near_middle_t_s.push_back(t_s[piece[trough]]);
    if (value <= rest_limit_deg) {
      bounds.push_back(trough);
      bound_near.push_back(near);
    } else if (near) {
      inner_near.push_back(trough);
    }
  }
  bounds.push_back(end);
  bound_near.push_back(false);
  const std::vector<double> piece_speeds = speeds(piece, t_s, angle_deg);
  for (std::size_t k = 0; k + 1 < bounds.size(); ++k) {
    Repetition rep = describe(piece, t_s, angle_deg, piece_speeds, bounds[k], bounds[k + 1]);
    const bool cut = k == 0 || k + 2 == bounds.size();  // by the start or the end of the piece
    if (cut) {
      if (rep.range_deg < options.hysteresis_deg) continue;
      rep.partial = true;
    } else {
      rep.partial = !is_complete(rep, angle_deg[piece[bounds[k]]], angle_deg[piece[bounds[k + 1]]], options);
    }
    rep.cut_ambiguity_deg = cut_ambiguity_deg(piece, angle_deg, bounds, bound_near, inner_near, k);
    out.push_back(rep);
  }
}

// Appends the repetitions of one piece of an angle that swings about its zero (a trunk tilted
// right then left, a forearm rolled into pronation then supination): each runs from the last
// sample at rest (within the hysteresis of `rest_deg`) before the angle leaves it, to the first
// sample back at rest, by at least the hysteresis from the side it comes from, once the angle has
// been out on both sides. Crossing the rest on the way from one side to the other is not a
// return. An excursion to one side only that comes back to rest and then leaves to that same side
// again ended where it came back (a crossing would go on to the other side): it is partial, and
// the angle's next excursion starts afresh. Motion cut by the start or the end of the piece is
// partial, as is a repetition whose range or duration falls outside the bounds.
void add_piece_about_zero(const Piece& piece, const std::vector<double>& t_s, const std::vector<double>& angle_deg,
                          double rest_deg, const RepetitionOptions& options, std::vector<Repetition>& out) {
  const std::vector<double> piece_speeds = speeds(piece, t_s, angle_deg);
  constexpr int kBothSides = 3;
  bool out_of_rest = false, cut_by_start = false, rest_seen = false;
  int sides_seen = 0, last_side = 0;
  // Distances from the rest: the largest since the angle went out on last_side, the smallest since
  // it came back to rest.
  double last_side_extreme_deg = 0;
  double rest_minimum_deg = 0;
  std::size_t first = 0;  // where the current excursion left rest
  std::size_t last_at_rest = 0;
  // Whether an excursion that has been out on one side only is back at rest, and where it came back.
  bool back_from_one_side = false;
  std::size_t came_back_at = 0;
  // Whether the current excursion, cut by the start, came back to rest from one side and then
  // crossed to the other: a settled start joined to the first swing, or a swing under way.
  bool crossed_after_return_from_start = false;
  // Leaving rest takes a real move (the hysteresis) from where the angle rested, so noise just
  // after a return does not start the next excursion.
  const auto still_at_rest = [&](int side, double magnitude) {
    return side == 0 || magnitude - rest_minimum_deg < options.hysteresis_deg;
  };
  for (std::size_t p = 0; p < piece.size(); ++p) {
    const double deviation = angle_deg[piece[p]] - rest_deg;
    const double magnitude = std::abs(deviation);
    const int side = magnitude < options.hysteresis_deg ? 0 : deviation > 0 ? 1 : 2;
    if (!out_of_rest) {
      if (side == 0 || (rest_seen && still_at_rest(side, magnitude))) {
        if (side == 0) last_at_rest = p;
        rest_minimum_deg = rest_seen ? std::min(rest_minimum_deg, magnitude) : magnitude;
        rest_seen = rest_seen || side == 0;
        continue;
      }
      out_of_rest = true;
      cut_by_start = !rest_seen;
      first = rest_seen ? last_at_rest : 0;
      sides_seen = last_side = side;
      last_side_extreme_deg = magnitude;
      continue;
    }
    if (back_from_one_side) {
      if (still_at_rest(side, magnitude)) {
        if (side == 0) last_at_rest = p;
        rest_minimum_deg = std::min(rest_minimum_deg, magnitude);
        continue;
      }
      if (side == last_side) {
        // Out to the side it came back from: that excursion is over, not on its way across (a
        // series that starts out of rest, settles, and whose first swing goes the same way).
        Repetition rep = describe(piece, t_s, angle_deg, piece_speeds, first, came_back_at);
        rep.partial = true;
        out.push_back(rep);
        cut_by_start = false;
        first = last_at_rest;
        sides_seen = last_side = side;
        last_side_extreme_deg = magnitude;
        back_from_one_side = false;
        continue;
      }
      back_from_one_side = false;  // on to the other side: a crossing, or a rest within the swing
      crossed_after_return_from_start = cut_by_start;
    }
    if (side != 0) {
      last_side_extreme_deg = side == last_side ? std::max(last_side_extreme_deg, magnitude) : magnitude;
      last_side = side;
      sides_seen |= side;
    }
    // Back at rest, and by a real reversal (the hysteresis) from the last side: noise where the
    // angle just reached that side must not end the repetition there.
    const bool returned = side == 0 && last_side_extreme_deg - magnitude >= options.hysteresis_deg;
    if (returned && sides_seen != kBothSides) {
      back_from_one_side = true;
      came_back_at = p;
      last_at_rest = p;
      rest_minimum_deg = magnitude;
      continue;
    }
    if (!returned) continue;
    Repetition rep = describe(piece, t_s, angle_deg, piece_speeds, first, p);
    rep.partial = cut_by_start || !duration_within_bounds(rep, options) || rep.range_deg < options.min_amplitude_deg;
    rep.may_hold_repetition = crossed_after_return_from_start;
    out.push_back(rep);
    out_of_rest = false;
    crossed_after_return_from_start = false;
    rest_seen = true;  // even if the piece started out of rest: the next leave starts from here
    last_at_rest = p;
    rest_minimum_deg = magnitude;
  }
  if (!out_of_rest) return;
  // An excursion to one side that came back to rest ends there: what follows is the rest.
  Repetition rep =
      describe(piece, t_s, angle_deg, piece_speeds, first, back_from_one_side ? came_back_at : piece.size() - 1);
  if (rep.range_deg < options.hysteresis_deg) return;  // noise at the end, not motion
  rep.partial = true;
  out.push_back(rep);
}

double mean(const std::vector<double>& values) {
  if (values.empty()) return 0.0;
  double sum = 0.0;
  for (double v : values) sum += v;
  return sum / static_cast<double>(values.size());
}

// Sample standard deviation (n - 1); 0 for fewer than two values, where there is no spread to see.
double spread(const std::vector<double>& values) {
  if (values.size() < 2) return 0.0;
  const double m = mean(values);
  double sum_sq = 0.0;
  for (double v : values) sum_sq += (v - m) * (v - m);
  return std::sqrt(sum_sq / static_cast<double>(values.size() - 1));
}

// The confidence of a repetition's range: the lower of the confidences at its lowest and highest
// samples (the first of equals). A repetition never spans a cut, so every finite sample between
// its start and end belongs to it.
double range_confidence(const Repetition& rep, const std::vector<double>& t_s, const std::vector<double>& angle_deg,
                        const std::vector<float>& confidence) {
  std::optional<double> at_min, at_max;
  const auto first = static_cast<std::size_t>(std::lower_bound(t_s.begin(), t_s.end(), rep.t_start_s) - t_s.begin());
  for (std::size_t i = first; i < t_s.size() && t_s[i] <= rep.t_end_s && !(at_min && at_max); ++i) {
    if (!at_min && angle_deg[i] == rep.min_deg) at_min = confidence[i];
    if (!at_max && angle_deg[i] == rep.max_deg) at_max = confidence[i];
  }
  return std::min(at_min.value_or(0.0), at_max.value_or(0.0));
}

// The share of a series' finite samples at confidence >= kConfidentAt: 1 without confidences, 0
// without finite samples.
double confident_fraction(const std::vector<double>& angle_deg, const std::vector<float>& confidence) {
  if (confidence.empty()) return 1.0;
  std::size_t finite = 0, confident = 0;
  for (std::size_t i = 0; i < angle_deg.size(); ++i) {
    if (!std::isfinite(angle_deg[i])) continue;
    ++finite;
    if (confidence[i] >= kConfidentAt) ++confident;
  }
  return finite > 0 ? static_cast<double>(confident) / static_cast<double>(finite) : 0.0;
}

// Each repetition's confidence (its samples' and its cut's), the share of confident samples and the
// uncertain counted ones.
void add_confidences(RepetitionSummary& summary, const std::vector<double>& t_s, const std::vector<double>& angle_deg,
                     const std::vector<float>& confidence) {
  summary.confident_fraction = confident_fraction(angle_deg, confidence);
  for (Repetition& rep : summary.repetitions) {
    const double of_samples = confidence.empty() ? 1.0 : range_confidence(rep, t_s, angle_deg, confidence);
    rep.confidence =
        std::min(of_samples, forearm::confidence_from_bound99_rad(rep.cut_ambiguity_deg * std::numbers::pi / 180.0));
    if (!rep.partial && rep.confidence < kConfidentAt) ++summary.uncertain_count;
  }
}

void summarize(RepetitionSummary& summary) {
  std::vector<double> ranges, durations, peak_speeds;
  for (const Repetition& rep : summary.repetitions) {
    if (rep.partial) continue;
    ranges.push_back(rep.range_deg);
    durations.push_back(rep.duration_s);
    peak_speeds.push_back(rep.peak_speed_deg_s);
  }
  summary.count = static_cast<int>(ranges.size());
  summary.mean_range_deg = mean(ranges);
  summary.range_spread_deg = spread(ranges);
  summary.mean_duration_s = mean(durations);
  summary.duration_spread_s = spread(durations);
  summary.mean_peak_speed_deg_s = mean(peak_speeds);
}

// The finite values of a series, in ascending order.
std::vector<double> sorted_finite(const std::vector<double>& series) {
  std::vector<double> finite;
  for (double v : series) {
    if (std::isfinite(v)) finite.push_back(v);
  }
  std::sort(finite.begin(), finite.end());
  return finite;
}

// The series' range of motion between its 5th and 95th percentiles of finite samples (as
// dominant_series, so that a glitch cannot move it), from the sorted finite samples.
struct MotionRange {
  double low = 0, high = 0;
  double middle() const { return 0.5 * (low + high); }
  // The middle half: the range moved a quarter of its spread inwards at both ends.
  double middle_half_low() const { return low + 0.25 * (high - low); }
  double middle_half_high() const { return high - 0.25 * (high - low); }
};

MotionRange motion_range(const std::vector<double>& sorted) {
  return {percentile(sorted, 0.05), percentile(sorted, 0.95)};
}

bool zero_in_middle_half(const MotionRange& range) {
  return range.high > range.low && range.middle_half_low() <= 0.0 && 0.0 <= range.middle_half_high();
}

// Where an angle that swings about its zero rests: the median of its samples in the middle half
// of its motion, where it holds between repetitions. Not zero itself: a fitted angle can be
// offset by several degrees, more than the hysteresis, and would then never seem to come back.
double middle_rest_deg(const std::vector<double>& sorted, const MotionRange& range) {
  std::vector<double> middle;
  for (double v : sorted)
    if (v >= range.middle_half_low() && v <= range.middle_half_high()) middle.push_back(v);
  return middle.empty() ? 0.0 : percentile(middle, 0.5);
}

}  // namespace

double counted_amplitude_deg(const RepetitionOptions& options, double spread_deg) {
  return std::min(options.min_amplitude_deg, std::max(2 * options.hysteresis_deg, 0.5 * spread_deg));
}

bool swings_about_zero(const std::vector<double>& angle_deg) {
  const std::vector<double> finite = sorted_finite(angle_deg);
  return finite.size() >= 2 && zero_in_middle_half(motion_range(finite));
}

RepetitionSummary segment_repetitions(const std::vector<double>& t_s, const std::vector<double>& angle_deg,
                                      const RepetitionOptions& options, const std::vector<float>& confidence) {
  check_series(t_s, angle_deg);
  check_confidence(confidence, t_s, "t_s");
  check_options(options);
  RepetitionSummary summary;
  const std::vector<double> finite = sorted_finite(angle_deg);
  const bool has_range = finite.size() >= 2;
  const MotionRange range = has_range ? motion_range(finite) : MotionRange{};
  const bool about_zero = has_range && zero_in_middle_half(range);
  // Only troughs in the resting half, at most the middle of the range, bound repetitions (any
  // trough where there are fewer than two samples to give a range).
  const double rest_limit_deg = has_range ? range.middle() : std::numeric_limits<double>::infinity();
  const double rest_deg = about_zero ? middle_rest_deg(finite, range) : 0.0;
  RepetitionOptions counted = options;
  counted.min_amplitude_deg = counted_amplitude_deg(options, range.high - range.low);
  for (const Piece& piece : split_at_gaps(t_s, angle_deg, options.max_gap_s)) {
    if (about_zero) {
      add_piece_about_zero(piece, t_s, angle_deg, rest_deg, counted, summary.repetitions);
    } else {
      add_piece(piece, t_s, angle_deg, counted, rest_limit_deg, summary.repetitions, summary.troughs_near_middle_t_s);
    }
  }
  summarize(summary);
  add_confidences(summary, t_s, angle_deg, confidence);
  return summary;
}

int dominant_series(const std::vector<std::vector<double>>& angle_series_deg,
                    const std::vector<std::vector<float>>& confidence, double min_amplitude_deg) {
  if (!confidence.empty() && confidence.size() != angle_series_deg.size()) {
    throw_invalid("confidence", "has " + std::to_string(confidence.size()) + " series but angle_series_deg has " +
                                    std::to_string(angle_series_deg.size()) + "; give one per angle series or none");
  }
  // An angle defined in only a few frames (pronation where a nearly straight elbow crosses the
  // flexion bound for a moment, its plane then ill-conditioned) describes no exercise, however far
  // those values scatter: only series defined in at least half as many frames as the most
  // defined one compete.
  std::vector<std::vector<double>> finite_series;
  std::size_t most_defined = 0;
  for (std::size_t s = 0; s < angle_series_deg.size(); ++s) {
    if (!confidence.empty())
      check_confidence(confidence[s], angle_series_deg[s], "angle_series_deg[" + std::to_string(s) + "]");
    finite_series.push_back(sorted_finite(angle_series_deg[s]));
    most_defined = std::max(most_defined, finite_series.back().size());
  }
  struct Candidate {
    std::size_t series;
    double spread_deg;
    bool confident;
  };
  std::vector<Candidate> candidates;
  bool confident_one_moves = false;
  for (std::size_t s = 0; s < finite_series.size(); ++s) {
    const std::vector<double>& finite = finite_series[s];
    if (finite.size() < 2 || 2 * finite.size() < most_defined) continue;
    // Percentiles rather than max - min, so that a few outliers (a tracking glitch) cannot make a
    // still joint look like the one that moves.
    const double spread_deg = percentile(finite, 0.95) - percentile(finite, 0.05);
    const bool confident = confidence.empty() || 2 * confident_fraction(angle_series_deg[s], confidence[s]) >= 1.0;
    candidates.push_back({s, spread_deg, confident});
    confident_one_moves = confident_one_moves || (confident && spread_deg >= min_amplitude_deg);
  }
  int best = -1;
  double best_spread = 0.0;
  for (const Candidate& candidate : candidates) {
    // A series mostly below confidence (the fit's elbow flexion near full extension, whose values
    // scatter with the arm lengths) describes the exercise only when no confident one moves enough
    // to make a repetition; otherwise its spread is the method's doubt, not the patient's motion.
    if (confident_one_moves && !candidate.confident) continue;
    if (best < 0 || candidate.spread_deg > best_spread) {  // ties go to the first
      best = static_cast<int>(candidate.series);
      best_spread = candidate.spread_deg;
    }
  }
  return best;
}

}  // namespace posefuse::measures
