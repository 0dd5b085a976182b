#pragma once
// Repetitions of an exercise and the range of motion of each, segmented on one joint angle over
// time (docs/measures.md, "Repetitions").
//
// A repetition is one excursion of the angle away from its resting end and back: a trough, the
// next peak, the next trough (for an angle whose rest is its low end, e.g. elbow flexion or
// shoulder elevation). Turning points are found with hysteresis: a peak is confirmed once the
// angle has fallen `hysteresis_deg` below the running maximum, a trough once it has risen that
// much above the running minimum, so noise smaller than the hysteresis never makes a turn.
// Only troughs in the resting half of the motion bound repetitions: at most the middle of the
// series' range (halfway between its 5th and 95th percentiles). A dip while the limb is held
// away from rest (a wobble at the top of a raise, the strokes of hair combing) belongs to the
// repetition it happens in instead of splitting it into partial pieces.
// A trough -> peak -> trough cycle counts when both of its swings are at least the counted
// amplitude (counted_amplitude_deg: `min_amplitude_deg`, or half the motion of a series that moves
// less than twice that) and its duration lies within [min_duration_s, max_duration_s]; a cycle cut by
// the start or the end of the series, by missing samples (NaN) longer than `max_gap_s`, or that
// falls short of the amplitude or duration bounds is kept as partial: reported, not counted.
//
// In detail:
// - Missing samples (NaN) are skipped. Wherever two consecutive finite samples are more than
//   `max_gap_s` apart (a NaN stretch, or a jump in the timestamps) the series is cut, and each
//   piece is segmented on its own: a cycle spanning the cut ends up as two partial pieces.
// - The motion before a piece's first trough and after its last one is reported as a partial
//   repetition when its range reaches `hysteresis_deg` (smaller is noise, not reported).
// - A recording usually stops at rest, where nothing rises again to confirm the last trough: a
//   final descent that has come back to within `hysteresis_deg` of the trough its cycle started
//   from ends that cycle at its lowest sample; one that has not is partial.
//
// An angle that swings about its zero instead (swings_about_zero: a trunk tilted right then left,
// a forearm rolled into pronation then supination) rests in the middle of its motion, where the
// rules above would cut each repetition at its far side. It rests where its samples in the middle
// half of the motion have their median (a fitted angle may rest several degrees off zero). Its
// repetition runs from the last sample at rest (within `hysteresis_deg` of that) before the angle
// leaves, out to both sides, to the first sample back at rest (and by at least `hysteresis_deg`
// from the side it comes from); passing the rest on the way from one side to the other is not a
// return. An excursion to one side only that comes back to rest and then leaves to that same side
// again has ended where it came back, since a crossing would go on to the other side (a series
// that starts out of rest and settles before its first swing); it is partial. Leaving rest,
// between repetitions or after such a return, takes a real move: at least `hysteresis_deg` from
// where the angle came closest to rest. A settled start whose first swing goes the other way
// cannot be told from a slow crossing and stays joined to it, a partial repetition marked
// may_hold_repetition. A repetition counts when its range (max - min) is at least the counted
// amplitude and its duration lies within the bounds; motion cut by the start, the end or
// a gap is partial, as above.
//
// Confidence: segmenting does not look at the samples' confidences (an angle the method is unsure
// of still moves as the exercise does); it reports them. Each repetition's range carries the
// confidence of its two extremes and of its cut (cut_ambiguity_deg), and the summary how much of the series was
// confident, so that a count or range read off values not to act on says so (docs/measures.md, "Confidence of
// repetitions"). Choosing the angle does look at them (dominant_series).
#include <vector>

namespace posefuse::measures {

struct RepetitionOptions {
  double hysteresis_deg = 5.0;      // smallest reversal that makes a turning point
  double min_amplitude_deg = 20.0;  // a swing this large always counts (counted_amplitude_deg)
  double min_duration_s = 0.5;      // trough to trough
  double max_duration_s = 30.0;     // may be infinite: no upper bound
  double max_gap_s = 0.5;           // missing (NaN) stretches longer than this cut the series;
                                    // may be infinite: never cut
};

struct Repetition {
  double t_start_s = 0, t_end_s = 0;  // the troughs that bound it (series time, seconds)
  double t_peak_s = 0;                // its highest sample (the first of equals)
  double min_deg = 0, max_deg = 0;    // over the repetition
  double range_deg = 0;               // max - min
  double peak_speed_deg_s = 0;        // largest |d angle / dt| at its samples (central differences
                                      // over the neighbouring finite samples; one-sided at a cut)
  double duration_s = 0;              // t_end - t_start
  bool partial = false;               // reported, not counted
  // A partial repetition cut by the start of an angle that swings about its zero, which came back
  // to rest from one side and then crossed to the other before its return: a settled start (a
  // subject, or a fit, coming to rest) joined to the first swing, which would hold one repetition
  // more, or a swing already under way when the recording began; the two look the same.
  bool may_hold_repetition = false;
  // How much its range would change were the turns within `hysteresis_deg` of the middle of the
  // range (troughs_near_middle_t_s) that bound it or lie inside it read the other way: bounding
  // ones as no ends (the repetition runs on past them to the nearest other bound), inner ones as
  // ends (the repetition keeps the part that holds its peak). 0 where no such turn touches it.
  double cut_ambiguity_deg = 0;
  // Of its range: the lower of the confidences at its lowest and highest samples (the range is
  // their difference, so an error in either moves it; 1 where the series carries no confidences),
  // and at most that of an error whose 99 % bound is cut_ambiguity_deg (2^-(bound / 15 deg)^2):
  // either reading of such a turn is as likely, so the range may be off by that much.
  double confidence = 1.0;
};

struct RepetitionSummary {
  std::vector<Repetition> repetitions;  // in time order, partial ones included
  int count = 0;                        // complete repetitions only
  // Over the counted repetitions (0 when none; spread is the sample standard deviation, 0 for one).
  double mean_range_deg = 0, range_spread_deg = 0;
  double mean_duration_s = 0, duration_spread_s = 0;
  double mean_peak_speed_deg_s = 0;
  // The share of the series' finite samples at confidence >= kConfidentAt (1 without confidences),
  // and how many counted repetitions have a confidence below it.
  double confident_fraction = 1.0;
  int uncertain_count = 0;
  // Times (series seconds) of the troughs of an angle that rests at one end which lie within
  // `hysteresis_deg` of the middle of its range, the bound below which a trough ends a repetition:
  // whether they end one turns on a few degrees (a hold half way, such as paper 1's protocol at
  // 90 degrees of elevation), so the repetitions may be cut elsewhere than the motion's own.
  std::vector<double> troughs_near_middle_t_s;
};

// `t_s` strictly increasing, same size as `angle_deg`; NaN marks a missing sample. `confidence`:
// each sample's, in [0, 1], or empty (every sample fully confident). Throws posefuse::Error
// (kInvalidArgument, field "t_s" / "angle_deg" / "confidence" / "repetition_options.*") for
// mismatched sizes, non-increasing or non-finite times, infinite angles, confidences outside
// [0, 1] and bad options:
// hysteresis_deg not positive, min_amplitude_deg below hysteresis_deg, min_duration_s negative,
// max_duration_s below min_duration_s (named as "repetition_options.max_duration_s"), max_gap_s
// negative, or any of them NaN. An empty or all-NaN series has no repetitions.
RepetitionSummary segment_repetitions(const std::vector<double>& t_s, const std::vector<double>& angle_deg,
                                      const RepetitionOptions& options = {}, const std::vector<float>& confidence = {});

// The amplitude a swing needs to count in a series whose motion (the spread between its 5th and
// 95th percentiles of finite samples, as dominant_series) is `spread_deg`: `min_amplitude_deg`, or,
// for a series that moves less than twice that (a shrug, a patient whose range is small), half its
// motion: the middle of its range, the bound that troughs already keep to, so a counted swing
// reaches from the resting half into the moving one. Never below twice `hysteresis_deg` (nor above
// `min_amplitude_deg`): each end of a swing is known only to the hysteresis, so a smaller swing can
// be noise at both ends. A fixed threshold alone would decide whether a motion as large as it
// counts by its noise.
double counted_amplitude_deg(const RepetitionOptions& options, double spread_deg);

// Whether a series swings about the angle's zero (its anatomical neutral) rather than rising
// from a rest at one end: zero lies in the middle half of its motion, between its 5th and 95th
// percentiles of finite samples (as dominant_series) moved a quarter of their spread inwards.
bool swings_about_zero(const std::vector<double>& angle_deg);

// Index of the series that moves most: the largest spread between its 5th and 95th percentiles
// of finite samples (the exercise's dominant angle), so that a few outliers cannot make a still
// joint win; percentiles interpolate linearly between ranks, the first of equal spreads wins.
// Only series with at least half as many finite samples as the most complete one compete (a few
// values of an angle that is mostly undefined describe no exercise). With `confidence` (one
// series per angle series, as segment_repetitions takes them), a series with fewer than half of
// its finite samples at kConfidentAt competes only when no series that has that half spreads at
// least `min_amplitude_deg` (a swing that large always counts, counted_amplitude_deg; a confident
// angle that moves less, such as an arm brought into position, is no reason to pass over the
// unsure one that moves more): an angle the method is unsure of (a fitted elbow near full extension)
// can scatter more than the joint that moves, but it still describes the exercise when nothing
// confident moves enough to make a repetition (pronation whose mounting roll is unknown). -1 when
// no series has two finite samples. Throws posefuse::Error (kInvalidArgument, "confidence") for a
// confidence series count or size that does not pair up, or a confidence outside [0, 1].
int dominant_series(const std::vector<std::vector<double>>& angle_series_deg,
                    const std::vector<std::vector<float>>& confidence = {}, double min_amplitude_deg = 0.0);

}  // namespace posefuse::measures
