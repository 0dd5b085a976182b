// Repetitions and their range of motion on one joint angle (measures/repetitions.hpp).
#include "measures/repetitions.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <functional>
#include <limits>
#include <numbers>
#include <random>
#include <string>
#include <utility>
#include <vector>

#include "common/error.hpp"
#include "measures/joint_angles.hpp"

namespace posefuse::measures {
namespace {

constexpr double kPi = 3.14159265358979323846;
constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();
constexpr double kInf = std::numeric_limits<double>::infinity();
constexpr double kDt = 0.01;  // 100 Hz

struct Cycle {
  double amplitude_deg;
  double period_s;
};

// One excursion from rest and back: amplitude / 2 * (1 - cos), 0 at both ends, the peak halfway.
double lift(const Cycle& cycle, double phase_s) {
  return cycle.amplitude_deg / 2 * (1 - std::cos(2 * kPi * phase_s / cycle.period_s));
}

// The peak of |d lift / dt|, a quarter of the way through.
double analytic_peak_speed(const Cycle& cycle) { return cycle.amplitude_deg / 2 * 2 * kPi / cycle.period_s; }

struct Series {
  std::vector<double> t_s, angle_deg;
};

// The cycles back to back, sampled at 100 Hz from t = 0 to the end of the last one (both troughs
// included). Sample k sits at exactly k * kDt; the troughs fall on samples when the periods are
// multiples of kDt.
// A series at 100 Hz from 0 deg at t = 0, built leg by leg: each goes linearly to `to_deg` over
// `samples` samples (a hold: to where it is).
struct PiecewiseLinear {
  Series series{{0.0}, {0.0}};
  void to(double to_deg, int samples) {
    const double from = series.angle_deg.back();
    for (int k = 1; k <= samples; ++k) {
      series.t_s.push_back(static_cast<double>(series.t_s.size()) * kDt);
      series.angle_deg.push_back(from + (to_deg - from) * k / samples);
    }
  }
};

Series exercise(const std::vector<Cycle>& cycles) {
  Series series;
  double cycle_start_s = 0;
  std::size_t k = 0;
  for (std::size_t c = 0; c < cycles.size(); ++c) {
    const double cycle_end_s = cycle_start_s + cycles[c].period_s;
    const bool last = c + 1 == cycles.size();
    for (;; ++k) {
      const double t = static_cast<double>(k) * kDt;
      // Half a sample of slack so that rounding in k * kDt never drops or doubles a trough.
      if (last ? t > cycle_end_s + kDt / 2 : t >= cycle_end_s - kDt / 2) break;
      series.t_s.push_back(t);
      series.angle_deg.push_back(lift(cycles[c], t - cycle_start_s));
    }
    cycle_start_s = cycle_end_s;
  }
  return series;
}

// Samples with t in [from_s, to_s] become missing.
void blank(Series& series, double from_s, double to_s) {
  for (std::size_t i = 0; i < series.t_s.size(); ++i) {
    if (series.t_s[i] >= from_s - 1e-9 && series.t_s[i] <= to_s + 1e-9) series.angle_deg[i] = kNaN;
  }
}

// Drops the samples after `to_s`.
void cut_after(Series& series, double to_s) {
  while (!series.t_s.empty() && series.t_s.back() > to_s + 1e-9) {
    series.t_s.pop_back();
    series.angle_deg.pop_back();
  }
}

RepetitionSummary segment(const Series& series, const RepetitionOptions& options = {}) {
  return segment_repetitions(series.t_s, series.angle_deg, options);
}

// Five identical 90 deg, 2 s cycles: five counted repetitions bounded by the troughs, each with its
// range, peak and peak speed as the formula gives them.
TEST(Repetitions, CleanCyclesAreEachCountedWithTheirRangeTimesAndSpeed) {
  const Cycle cycle{90, 2};
  const RepetitionSummary summary = segment(exercise(std::vector<Cycle>(5, cycle)));
  ASSERT_EQ(summary.count, 5);
  ASSERT_EQ(summary.repetitions.size(), 5u);
  for (std::size_t k = 0; k < 5; ++k) {
    const Repetition& rep = summary.repetitions[k];
    SCOPED_TRACE("repetition " + std::to_string(k));
    EXPECT_FALSE(rep.partial);
    EXPECT_NEAR(rep.t_start_s, 2.0 * static_cast<double>(k), 1e-9);
    EXPECT_NEAR(rep.t_end_s, 2.0 * static_cast<double>(k + 1), 1e-9);
    EXPECT_NEAR(rep.t_peak_s, 2.0 * static_cast<double>(k) + 1, 1e-9);
    EXPECT_NEAR(rep.duration_s, 2.0, 1e-9);
    EXPECT_NEAR(rep.min_deg, 0.0, 0.1);
    EXPECT_NEAR(rep.max_deg, 90.0, 0.1);
    EXPECT_NEAR(rep.range_deg, 90.0, 0.1);
    EXPECT_NEAR(rep.peak_speed_deg_s, analytic_peak_speed(cycle), 0.01 * analytic_peak_speed(cycle));
  }
  EXPECT_NEAR(summary.mean_range_deg, 90.0, 0.1);
  EXPECT_NEAR(summary.range_spread_deg, 0.0, 1e-6);
  EXPECT_NEAR(summary.mean_duration_s, 2.0, 1e-9);
  EXPECT_NEAR(summary.duration_spread_s, 0.0, 1e-6);
  EXPECT_NEAR(summary.mean_peak_speed_deg_s, analytic_peak_speed(cycle), 0.01 * analytic_peak_speed(cycle));
}

// Cycles of different sizes and paces: each keeps its own range, duration and speed, and the
// summary's means and sample spreads are theirs.
TEST(Repetitions, VaryingAmplitudesAndPeriodsAreMeasuredOneByOne) {
  const std::vector<Cycle> cycles = {{60, 1.5}, {90, 2.0}, {40, 3.0}, {120, 2.5}};
  const RepetitionSummary summary = segment(exercise(cycles));
  ASSERT_EQ(summary.count, 4);
  ASSERT_EQ(summary.repetitions.size(), 4u);
  double start_s = 0;
  for (std::size_t k = 0; k < cycles.size(); ++k) {
    const Repetition& rep = summary.repetitions[k];
    SCOPED_TRACE("repetition " + std::to_string(k));
    EXPECT_FALSE(rep.partial);
    EXPECT_NEAR(rep.t_start_s, start_s, 1e-9);
    EXPECT_NEAR(rep.t_peak_s, start_s + cycles[k].period_s / 2, 1e-9);
    EXPECT_NEAR(rep.duration_s, cycles[k].period_s, 1e-9);
    EXPECT_NEAR(rep.range_deg, cycles[k].amplitude_deg, 0.1);
    EXPECT_NEAR(rep.peak_speed_deg_s, analytic_peak_speed(cycles[k]), 0.01 * analytic_peak_speed(cycles[k]));
    start_s += cycles[k].period_s;
  }
  // Ranges 60, 90, 40, 120: mean 77.5, sample spread sqrt(3675 / 3) = 35. Durations 1.5, 2, 3, 2.5:
  // mean 2.25, sample spread sqrt(1.25 / 3).
  EXPECT_NEAR(summary.mean_range_deg, 77.5, 0.1);
  EXPECT_NEAR(summary.range_spread_deg, 35.0, 0.1);
  EXPECT_NEAR(summary.mean_duration_s, 2.25, 1e-9);
  EXPECT_NEAR(summary.duration_spread_s, std::sqrt(1.25 / 3), 1e-9);
  double mean_speed = 0;
  for (const Cycle& cycle : cycles) mean_speed += analytic_peak_speed(cycle) / 4;
  EXPECT_NEAR(summary.mean_peak_speed_deg_s, mean_speed, 0.01 * mean_speed);
}

// Noise whose peak-to-peak is below the hysteresis (4 deg against 5) never makes a turn: the
// count, the ranges and the trough times stay. With the hysteresis below the noise the series
// gains partial pieces at rest, which shows that the hysteresis is what keeps them out.
TEST(Repetitions, NoiseBelowTheHysteresisDoesNotChangeTheCount) {
  Series series = exercise(std::vector<Cycle>(5, Cycle{90, 2}));
  std::mt19937 rng(20240611);
  std::uniform_real_distribution<double> noise(-2.0, 2.0);
  for (double& a : series.angle_deg) a += noise(rng);

  const RepetitionSummary summary = segment(series);
  ASSERT_EQ(summary.count, 5);
  ASSERT_EQ(summary.repetitions.size(), 5u);
  for (std::size_t k = 0; k < 5; ++k) {
    const Repetition& rep = summary.repetitions[k];
    SCOPED_TRACE("repetition " + std::to_string(k));
    EXPECT_FALSE(rep.partial);
    EXPECT_NEAR(rep.range_deg, 90.0, 4.0);
    // Within 4 deg of the bottom, 45 (1 - cos(pi t)) stays within 0.14 s of the trough.
    EXPECT_NEAR(rep.t_start_s, 2.0 * static_cast<double>(k), 0.15);
    EXPECT_NEAR(rep.t_end_s, 2.0 * static_cast<double>(k + 1), 0.15);
    EXPECT_NEAR(rep.t_peak_s, 2.0 * static_cast<double>(k) + 1, 0.15);
  }

  // With the hysteresis below the noise, the noise near rest makes turning points of its own:
  // small partial pieces between the repetitions. Those near the peaks lie above the middle of the
  // range and split nothing, so the five still count.
  RepetitionOptions twitchy;
  twitchy.hysteresis_deg = 1.0;
  const RepetitionSummary noisy = segment(series, twitchy);
  EXPECT_EQ(noisy.count, 5);
  EXPECT_GT(noisy.repetitions.size(), 5u);
}

// A recording usually ends at rest, with noise that never rises by the hysteresis: the last
// descent still ends the last repetition.
TEST(Repetitions, ARestingEndWithNoiseEndsTheLastRepetition) {
  Series series = exercise({{90, 2}, {90, 2}});
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> noise(-1.5, 1.5);
  for (int k = 1; k <= 150; ++k) {  // 1.5 s of rest after the last trough
    series.t_s.push_back(4.0 + k * kDt);
    series.angle_deg.push_back(0.0);
  }
  for (double& a : series.angle_deg) a += noise(rng);
  const RepetitionSummary summary = segment(series);
  EXPECT_EQ(summary.count, 2);
  ASSERT_EQ(summary.repetitions.size(), 2u);
  EXPECT_FALSE(summary.repetitions[1].partial);
  EXPECT_NEAR(summary.repetitions[1].range_deg, 90.0, 3.0);
}

// A swing of 10 deg between two repetitions turns (it is above the 5 deg hysteresis) but is below
// the 20 deg minimum amplitude: reported as partial, not counted, and the repetitions around it
// keep their own bounds.
TEST(Repetitions, AWiggleBelowTheMinimumAmplitudeIsPartial) {
  const RepetitionSummary summary = segment(exercise({{90, 2}, {10, 1}, {90, 2}}));
  EXPECT_EQ(summary.count, 2);
  ASSERT_EQ(summary.repetitions.size(), 3u);
  EXPECT_FALSE(summary.repetitions[0].partial);
  EXPECT_TRUE(summary.repetitions[1].partial);
  EXPECT_FALSE(summary.repetitions[2].partial);
  EXPECT_NEAR(summary.repetitions[1].t_start_s, 2.0, 1e-9);
  EXPECT_NEAR(summary.repetitions[1].t_end_s, 3.0, 1e-9);
  EXPECT_NEAR(summary.repetitions[1].range_deg, 10.0, 0.1);
  EXPECT_NEAR(summary.mean_range_deg, 90.0, 0.1);  // the wiggle is left out of the summary
  EXPECT_NEAR(summary.mean_duration_s, 2.0, 1e-9);
}

// The amplitude a swing needs follows the series' motion: half of it, between twice the
// hysteresis and the minimum amplitude.
TEST(Repetitions, TheCountedAmplitudeIsHalfTheMotionBetweenTwiceTheHysteresisAndTheMinimum) {
  const RepetitionOptions options;  // hysteresis 5, minimum amplitude 20
  EXPECT_EQ(counted_amplitude_deg(options, 0.0), 10.0);
  EXPECT_EQ(counted_amplitude_deg(options, 15.0), 10.0);
  EXPECT_EQ(counted_amplitude_deg(options, 30.0), 15.0);
  EXPECT_EQ(counted_amplitude_deg(options, 40.0), 20.0);
  EXPECT_EQ(counted_amplitude_deg(options, 150.0), 20.0);
  RepetitionOptions low = options;
  low.min_amplitude_deg = 8.0;  // below twice the hysteresis: the minimum still bounds it
  EXPECT_EQ(counted_amplitude_deg(low, 0.0), 8.0);
}

// A motion smaller than the minimum amplitude (a shrug, a patient with a small range) counts when
// each swing reaches half of the series' motion, and a motion exactly as large as the minimum no
// longer counts or not by a rounding of its swings. A swing well short of the rest is partial.
TEST(Repetitions, ASmallMotionCountsWhenItsSwingsReachHalfOfIt) {
  for (const double amplitude_deg : {12.0, 15.0, 19.9, 20.0}) {
    SCOPED_TRACE("amplitude " + std::to_string(amplitude_deg));
    const RepetitionSummary summary = segment(exercise(std::vector<Cycle>(3, Cycle{amplitude_deg, 2})));
    EXPECT_EQ(summary.count, 3);
    EXPECT_NEAR(summary.mean_range_deg, amplitude_deg, 0.1);
  }
  const RepetitionSummary with_short_one = segment(exercise({{15, 2}, {6, 1}, {15, 2}}));
  EXPECT_EQ(with_short_one.count, 2);
  ASSERT_EQ(with_short_one.repetitions.size(), 3u);
  EXPECT_TRUE(with_short_one.repetitions[1].partial);
}

// Noise at rest larger than the hysteresis makes turning points, but no swing twice the
// hysteresis: a still series counts nothing, however small its own motion.
TEST(Repetitions, NoiseAtRestCountsNothingThoughTheMotionIsSmall) {
  Series series;
  std::mt19937 rng(23);
  std::uniform_real_distribution<double> noise(-4.5, 4.5);
  for (int k = 0; k <= 1000; ++k) {
    series.t_s.push_back(k * kDt);
    series.angle_deg.push_back(30 + noise(rng));
  }
  const RepetitionSummary summary = segment(series);
  EXPECT_GT(summary.repetitions.size(), 0u);  // the noise does make turning points
  EXPECT_EQ(summary.count, 0);
}

// Reaches from a hold half way (paper 1's protocol holds the arm at 90 deg of elevation between
// its reaches): rest at 0 and reaches to 160 are held long enough to be the 5th and 95th
// percentiles, so the middle of the range is 80. A hold within the hysteresis of it is reported;
// one well below ends repetitions and one well above does not, and neither is reported.
TEST(Repetitions, TurnsNearTheMiddleOfTheRangeAreReported) {
  const auto reaches_from_a_hold = [](double hold_deg) {
    PiecewiseLinear legs;
    legs.to(0, 100);  // rest
    for (int r = 0; r < 3; ++r) {
      legs.to(160, 50);
      legs.to(160, 50);  // held at the top
      legs.to(hold_deg, 50);
      legs.to(hold_deg, 50);  // held half way
    }
    legs.to(0, 50);
    legs.to(0, 100);
    return legs.series;
  };
  const RepetitionSummary near = segment(reaches_from_a_hold(82));
  ASSERT_EQ(near.troughs_near_middle_t_s.size(), 2u);       // the holds between reaches; the last one falls to rest
  EXPECT_NEAR(near.troughs_near_middle_t_s[0], 2.5, 1e-9);  // where the first hold begins
  EXPECT_TRUE(segment(reaches_from_a_hold(40)).troughs_near_middle_t_s.empty());
  EXPECT_TRUE(segment(reaches_from_a_hold(120)).troughs_near_middle_t_s.empty());
  EXPECT_EQ(segment(reaches_from_a_hold(40)).count, 3);

  // A hold just below the middle cuts: the reach between the two holds (78 -> 160 -> 78) would be
  // the whole 0 -> 160 read the other way, so its range is off by up to 78 degrees and not
  // confident; the first and last reaches hold the whole excursion either way.
  const RepetitionSummary cut = segment(reaches_from_a_hold(78));
  ASSERT_EQ(cut.count, 3);
  std::vector<const Repetition*> counted;
  for (const Repetition& rep : cut.repetitions)
    if (!rep.partial) counted.push_back(&rep);
  ASSERT_EQ(counted.size(), 3u);
  EXPECT_NEAR(counted[1]->range_deg, 82, 1e-9);
  EXPECT_NEAR(counted[1]->cut_ambiguity_deg, 78, 1e-9);
  EXPECT_LT(counted[1]->confidence, 1e-6);
  for (const Repetition* rep : {counted[0], counted[2]}) {
    EXPECT_NEAR(rep->range_deg, 160, 1e-9);
    EXPECT_EQ(rep->cut_ambiguity_deg, 0);
    EXPECT_EQ(rep->confidence, 1);
  }
  EXPECT_EQ(cut.uncertain_count, 1);
  // Holds well away from the middle touch no range.
  for (const double hold_deg : {40.0, 120.0})
    for (const Repetition& rep : segment(reaches_from_a_hold(hold_deg)).repetitions) {
      EXPECT_EQ(rep.cut_ambiguity_deg, 0) << hold_deg;
      EXPECT_EQ(rep.confidence, 1) << hold_deg;
    }
}

// Read the other way, turns near the middle are no ends all at once: after a reach from rest (0)
// to 160, a hold at 78 with a 6 deg wobble in it makes two such turns in a row, and the next reach
// comes down to 20. That reach's range (140) would run back over both turns to the rest at 0
// (160), not only over the nearer one (whose range would stay 140).
TEST(Repetitions, TurnsNearTheMiddleInARowAreReadTheOtherWayTogether) {
  PiecewiseLinear legs;
  legs.to(0, 300);
  for (const auto& [to_deg, samples] : std::vector<std::pair<double, int>>{{160, 50},
                                                                           {160, 150},
                                                                           {78, 50},
                                                                           {78, 30},
                                                                           {84, 10},
                                                                           {78, 10},
                                                                           {78, 30},
                                                                           {160, 50},
                                                                           {160, 150},
                                                                           {20, 50},
                                                                           {20, 50},
                                                                           {160, 50},
                                                                           {160, 150},
                                                                           {0, 50},
                                                                           {0, 300}})
    legs.to(to_deg, samples);
  const RepetitionSummary summary = segment(legs.series);
  ASSERT_EQ(summary.troughs_near_middle_t_s.size(), 2u);
  const Repetition* after_wobble = nullptr;
  for (const Repetition& rep : summary.repetitions)
    if (!rep.partial && std::abs(rep.min_deg - 20) < 1e-9 && rep.t_start_s > summary.troughs_near_middle_t_s[1] - 1e-9)
      after_wobble = &rep;
  ASSERT_NE(after_wobble, nullptr);
  EXPECT_NEAR(after_wobble->range_deg, 140, 1e-9);
  EXPECT_NEAR(after_wobble->cut_ambiguity_deg, 20, 1e-9);
  EXPECT_LT(after_wobble->confidence, kConfidentAt);
}

// Turns near the middle inside a repetition, read as ends, would leave it the part that holds its
// peak: three reaches with dips to 82 between them (just above the middle, 80) keep the whole
// 0 -> 160 in the part that holds the highest one when that is the first, but only 160 - 82 when
// it is the middle one, between the two dips.
TEST(Repetitions, TurnsNearTheMiddleInsideARepetitionBoundItsRange) {
  const auto reaches_with_dips = [](const std::vector<double>& tops_deg) {
    PiecewiseLinear legs;
    legs.to(0, 200);
    for (int r = 0; r < 2; ++r) {
      for (std::size_t k = 0; k < tops_deg.size(); ++k) {
        if (k > 0) legs.to(82, 50);
        legs.to(tops_deg[k], 50);
        legs.to(tops_deg[k], 100);
      }
      legs.to(0, 50);
      legs.to(0, 200);
    }
    return legs.series;
  };
  for (const auto& [tops, ambiguity] :
       {std::pair{std::vector<double>{160, 150, 150}, 0.0}, std::pair{std::vector<double>{150, 160, 150}, 82.0}}) {
    const RepetitionSummary summary = segment(reaches_with_dips(tops));
    EXPECT_EQ(summary.troughs_near_middle_t_s.size(), 4u) << ambiguity;
    ASSERT_EQ(summary.count, 2) << ambiguity;
    for (const Repetition& rep : summary.repetitions) {
      if (rep.partial) continue;
      EXPECT_NEAR(rep.range_deg, 160, 1e-9) << ambiguity;
      EXPECT_NEAR(rep.cut_ambiguity_deg, ambiguity, 1e-9);
      EXPECT_EQ(rep.confidence<kConfidentAt, ambiguity> 15) << ambiguity;
    }
  }
}

// A raise held at the top with a 30 deg dip in it (hair combing's strokes, a wobble of the fit):
// the dip's trough lies above the middle of the range, so it bounds no repetition and each raise
// counts once, its range the whole excursion.
TEST(Repetitions, ADipWhileHeldAwayFromRestIsPartOfTheRepetition) {
  Series series;
  for (int r = 0; r < 3; ++r) {
    for (int k = 0; k < 400; ++k) {  // 4 s: raise 0 -> 150, dip to 120 and back, lower
      const double u = k / 400.0;
      const double raise = u < 0.25   ? 150 * std::sin(u / 0.25 * kPi / 2)
                           : u > 0.75 ? 150 * std::sin((1 - u) / 0.25 * kPi / 2)
                                      : 150;
      const double dip = (u > 0.4 && u < 0.6) ? 15 * (1 - std::cos((u - 0.4) / 0.2 * 2 * kPi)) : 0;
      series.t_s.push_back((r * 400 + k) * kDt);
      series.angle_deg.push_back(raise - dip);
    }
  }
  series.t_s.push_back(1200 * kDt);
  series.angle_deg.push_back(0);
  const RepetitionSummary summary = segment(series);
  EXPECT_EQ(summary.count, 3);
  ASSERT_EQ(summary.repetitions.size(), 3u);
  for (const Repetition& rep : summary.repetitions) {
    EXPECT_FALSE(rep.partial);
    EXPECT_NEAR(rep.range_deg, 150.0, 0.1);
    EXPECT_NEAR(rep.duration_s, 4.0, 0.02);
  }
}

// A wiggle smaller than the hysteresis is no turn at all: it is part of the repetition around it.
TEST(Repetitions, AWiggleBelowTheHysteresisIsNoRepetition) {
  const RepetitionSummary summary = segment(exercise({{90, 2}, {3, 1}, {90, 2}}));
  EXPECT_EQ(summary.count, 2);
  EXPECT_EQ(summary.repetitions.size(), 2u);
}

// The duration bounds: a 0.3 s flick is too fast, a 3 s cycle too slow once max_duration_s is 2.5.
TEST(Repetitions, CyclesOutsideTheDurationBoundsArePartial) {
  RepetitionOptions options;
  options.max_duration_s = 2.5;
  const RepetitionSummary summary = segment(exercise({{90, 2}, {60, 0.3}, {90, 3}, {90, 2}}), options);
  EXPECT_EQ(summary.count, 2);
  ASSERT_EQ(summary.repetitions.size(), 4u);
  EXPECT_FALSE(summary.repetitions[0].partial);
  EXPECT_TRUE(summary.repetitions[1].partial);
  EXPECT_NEAR(summary.repetitions[1].duration_s, 0.3, 1e-9);
  EXPECT_TRUE(summary.repetitions[2].partial);
  EXPECT_NEAR(summary.repetitions[2].duration_s, 3.0, 1e-9);
  EXPECT_FALSE(summary.repetitions[3].partial);
  EXPECT_NEAR(summary.mean_duration_s, 2.0, 1e-9);
}

// A series cut at the top of its fourth repetition, or halfway down from it: three counted, and
// the fourth reported as partial from its trough to the last sample.
TEST(Repetitions, ASeriesCutMidRepetitionEndsWithAPartialOne) {
  for (double cut_s : {7.0, 7.5}) {
    SCOPED_TRACE("cut at " + std::to_string(cut_s) + " s");
    Series series = exercise(std::vector<Cycle>(4, Cycle{90, 2}));
    cut_after(series, cut_s);
    const RepetitionSummary summary = segment(series);
    EXPECT_EQ(summary.count, 3);
    ASSERT_EQ(summary.repetitions.size(), 4u);
    const Repetition& last = summary.repetitions.back();
    EXPECT_TRUE(last.partial);
    EXPECT_NEAR(last.t_start_s, 6.0, 1e-9);
    EXPECT_NEAR(last.t_end_s, cut_s, 1e-9);
    EXPECT_NEAR(last.t_peak_s, 7.0, 1e-9);
    EXPECT_NEAR(last.range_deg, 90.0, 0.1);
    EXPECT_NEAR(summary.mean_range_deg, 90.0, 0.1);
  }
}

// A final rise that never comes back is partial when it reaches the hysteresis, and nothing when
// it does not.
TEST(Repetitions, AFinalRiseIsPartialOnlyWhenItReachesTheHysteresis) {
  Series series = exercise({{90, 2}, {90, 2}, {90, 2}});
  cut_after(series, 4.5);  // halfway up the third: 45 deg
  RepetitionSummary summary = segment(series);
  EXPECT_EQ(summary.count, 2);
  ASSERT_EQ(summary.repetitions.size(), 3u);
  EXPECT_TRUE(summary.repetitions[2].partial);
  EXPECT_NEAR(summary.repetitions[2].range_deg, 45.0, 0.1);

  series = exercise({{90, 2}, {90, 2}, {90, 2}});
  cut_after(series, 4.1);  // 45 (1 - cos(0.1 pi)) = 2.2 deg up the third
  summary = segment(series);
  EXPECT_EQ(summary.count, 2);
  EXPECT_EQ(summary.repetitions.size(), 2u);
}

// Motion before the first trough: a series that starts at the top of a repetition reports its
// descent as partial; one that starts a little above rest reports nothing for it.
TEST(Repetitions, LeadingMotionBeforeTheFirstTroughIsPartial) {
  Series series = exercise(std::vector<Cycle>(3, Cycle{90, 2}));
  Series from_peak, near_rest;
  for (std::size_t i = 0; i < series.t_s.size(); ++i) {
    if (series.t_s[i] >= 1.0 - 1e-9) {
      from_peak.t_s.push_back(series.t_s[i]);
      from_peak.angle_deg.push_back(series.angle_deg[i]);
    }
    if (series.t_s[i] >= 1.9 - 1e-9) {  // 2.2 deg above the trough at 2 s
      near_rest.t_s.push_back(series.t_s[i]);
      near_rest.angle_deg.push_back(series.angle_deg[i]);
    }
  }
  RepetitionSummary summary = segment(from_peak);
  EXPECT_EQ(summary.count, 2);
  ASSERT_EQ(summary.repetitions.size(), 3u);
  EXPECT_TRUE(summary.repetitions[0].partial);
  EXPECT_NEAR(summary.repetitions[0].t_start_s, 1.0, 1e-9);
  EXPECT_NEAR(summary.repetitions[0].t_end_s, 2.0, 1e-9);
  EXPECT_NEAR(summary.repetitions[0].range_deg, 90.0, 0.1);
  EXPECT_FALSE(summary.repetitions[1].partial);
  EXPECT_NEAR(summary.repetitions[1].t_start_s, 2.0, 1e-9);

  summary = segment(near_rest);
  EXPECT_EQ(summary.count, 2);
  ASSERT_EQ(summary.repetitions.size(), 2u);
  EXPECT_NEAR(summary.repetitions[0].t_start_s, 2.0, 1e-9);
}

// One second missing across the peak of the second repetition (more than max_gap_s = 0.5): the
// series is cut there and that repetition becomes two partial halves; the others still count.
TEST(Repetitions, AGapLongerThanMaxGapSplitsARepetitionIntoPartials) {
  Series series = exercise(std::vector<Cycle>(3, Cycle{90, 2}));
  blank(series, 2.5, 3.5);
  const RepetitionSummary summary = segment(series);
  EXPECT_EQ(summary.count, 2);
  ASSERT_EQ(summary.repetitions.size(), 4u);
  const Repetition& before = summary.repetitions[1];
  const Repetition& after = summary.repetitions[2];
  EXPECT_FALSE(summary.repetitions[0].partial);
  EXPECT_TRUE(before.partial);
  EXPECT_NEAR(before.t_start_s, 2.0, 1e-9);
  EXPECT_NEAR(before.t_end_s, 2.49, 1e-9);  // the last sample before the gap
  EXPECT_NEAR(before.range_deg, lift({90, 2}, 0.49), 0.1);
  EXPECT_TRUE(after.partial);
  EXPECT_NEAR(after.t_start_s, 3.51, 1e-9);  // the first sample after it
  EXPECT_NEAR(after.t_end_s, 4.0, 1e-9);
  EXPECT_FALSE(summary.repetitions[3].partial);
  EXPECT_NEAR(summary.repetitions[3].t_start_s, 4.0, 1e-9);

  // The same gap is bridged once max_gap_s allows it.
  RepetitionOptions lenient;
  lenient.max_gap_s = 2.0;
  EXPECT_EQ(segment(series, lenient).count, 3);
}

// A jump in the timestamps is missing data too, with or without NaN samples marking it.
TEST(Repetitions, AJumpInTimeCutsTheSeriesLikeAGap) {
  Series series = exercise(std::vector<Cycle>(3, Cycle{90, 2}));
  Series jumped;
  for (std::size_t i = 0; i < series.t_s.size(); ++i) {
    if (series.t_s[i] > 2.5 + 1e-9 && series.t_s[i] < 3.5 - 1e-9) continue;
    jumped.t_s.push_back(series.t_s[i]);
    jumped.angle_deg.push_back(series.angle_deg[i]);
  }
  const RepetitionSummary summary = segment(jumped);
  EXPECT_EQ(summary.count, 2);
  EXPECT_EQ(summary.repetitions.size(), 4u);
}

// Short stretches of missing samples (0.2 s here, and single samples) are stepped over: the count
// stays, and the range is that of the samples that are there.
TEST(Repetitions, ShortGapsAreBridged) {
  Series series = exercise(std::vector<Cycle>(3, Cycle{90, 2}));
  blank(series, 2.9, 3.1);          // across the second peak
  blank(series, 0.5, 0.5);          // where the first is fastest
  blank(series, 4.0, 4.0);          // the third's trough
  series.angle_deg.front() = kNaN;  // missing ends are simply not there
  series.angle_deg.back() = kNaN;
  const RepetitionSummary summary = segment(series);
  ASSERT_EQ(summary.count, 3);
  ASSERT_EQ(summary.repetitions.size(), 3u);
  EXPECT_NEAR(summary.repetitions[0].t_start_s, 0.01, 1e-9);
  EXPECT_NEAR(summary.repetitions[0].range_deg, 90.0, 0.1);
  // Central differences across the missing sample still give the peak speed.
  EXPECT_NEAR(summary.repetitions[0].peak_speed_deg_s, analytic_peak_speed({90, 2}),
              0.01 * analytic_peak_speed({90, 2}));
  EXPECT_NEAR(summary.repetitions[1].range_deg, lift({90, 2}, 0.89), 0.1);  // highest sample left
  EXPECT_FALSE(summary.repetitions[1].partial);
}

// Peak speed is read from central differences: on a 60 deg/s up-and-down ramp sampled at 10 Hz
// it is exactly 60, and a one-sample glitch of +10 deg at t = 0.3 s shows as (28 - 6) / 0.2 =
// 110 deg/s beside it (a one-sided difference would give 160).
TEST(Repetitions, PeakSpeedIsTheLargestCentralDifference) {
  std::vector<double> t, ramp;
  for (int i = 0; i <= 20; ++i) {
    t.push_back(0.1 * i);
    ramp.push_back(i <= 10 ? 6.0 * i : 6.0 * (20 - i));
  }
  RepetitionSummary summary = segment_repetitions(t, ramp);
  ASSERT_EQ(summary.count, 1);
  EXPECT_NEAR(summary.repetitions[0].peak_speed_deg_s, 60.0, 1e-9);
  EXPECT_NEAR(summary.repetitions[0].range_deg, 60.0, 1e-9);

  ramp[3] += 10;
  summary = segment_repetitions(t, ramp);
  ASSERT_EQ(summary.count, 1);
  EXPECT_NEAR(summary.repetitions[0].peak_speed_deg_s, 110.0, 1e-9);
}

TEST(Repetitions, EmptyStillAndMissingSeriesHaveNoRepetitions) {
  EXPECT_EQ(segment_repetitions({}, {}).repetitions.size(), 0u);
  EXPECT_EQ(segment_repetitions({0.0}, {30.0}).repetitions.size(), 0u);
  EXPECT_EQ(segment_repetitions({0.0, 0.1, 0.2}, {kNaN, kNaN, kNaN}).repetitions.size(), 0u);
  const RepetitionSummary still = segment_repetitions({0.0, 0.1, 0.2, 0.3}, {10.0, 12.0, 11.0, 13.0});
  EXPECT_EQ(still.repetitions.size(), 0u);
  EXPECT_EQ(still.count, 0);
  EXPECT_EQ(still.mean_range_deg, 0.0);
  EXPECT_EQ(still.mean_peak_speed_deg_s, 0.0);
}

// One counted repetition has a mean but no spread.
TEST(Repetitions, OneRepetitionHasNoSpread) {
  const RepetitionSummary summary = segment(exercise({{70, 2}}));
  ASSERT_EQ(summary.count, 1);
  EXPECT_NEAR(summary.mean_range_deg, 70.0, 0.1);
  EXPECT_EQ(summary.range_spread_deg, 0.0);
  EXPECT_EQ(summary.duration_spread_s, 0.0);
}

// Runs `call`, which must throw posefuse::Error (invalid argument) naming `field` and saying
// `words` somewhere in its message.
void expect_invalid(const std::function<void()>& call, const std::string& field, const std::string& words) {
  try {
    call();
    ADD_FAILURE() << "no error; expected one on " << field;
  } catch (const Error& e) {
    EXPECT_EQ(e.code(), ErrorCode::kInvalidArgument) << e.what();
    EXPECT_EQ(e.field(), field) << e.what();
    EXPECT_NE(std::string(e.what()).find(words), std::string::npos) << e.what();
  }
}

TEST(Repetitions, BadSeriesAreRefusedNamingTheField) {
  const std::vector<double> t = {0.0, 0.1, 0.2, 0.3};
  const std::vector<double> a = {0.0, 10.0, 20.0, 10.0};
  expect_invalid([&] { segment_repetitions(t, {0.0, 10.0, 20.0}); }, "angle_deg", "has 3 samples but t_s has 4");
  expect_invalid(
      [&] {
        segment_repetitions({0.0, 0.1, 0.05, 0.3}, a);
      },
      "t_s", "t_s[2] = 0.05 is not after t_s[1] = 0.1");
  expect_invalid(
      [&] {
        segment_repetitions({0.0, 0.1, 0.1, 0.3}, a);
      },
      "t_s", "t_s[2] = 0.1 is not after t_s[1] = 0.1");
  expect_invalid([&] { segment_repetitions({0.0, kNaN, 0.2, 0.3}, a); }, "t_s", "t_s[1] = nan is not a finite time");
  expect_invalid([&] { segment_repetitions({0.0, 0.1, 0.2, kInf}, a); }, "t_s", "t_s[3] = inf");
  expect_invalid(
      [&] {
        segment_repetitions(t, {0.0, kInf, 20.0, 10.0});
      },
      "angle_deg", "angle_deg[1] = inf is infinite");
  expect_invalid([&] { segment_repetitions(t, {0.0, 10.0, -kInf, 10.0}); }, "angle_deg", "angle_deg[2] = -inf");
}

// Confidences are reported, not used to segment: each repetition carries the lower of the
// confidences at its lowest and highest samples, the summary the share of confident samples and
// how many counted repetitions fall below kConfidentAt.
TEST(Repetitions, EachRepetitionCarriesTheConfidenceOfItsExtremes) {
  const Series series = exercise(std::vector<Cycle>(4, Cycle{90, 2}));
  std::vector<float> confidence(series.t_s.size(), 0.9f);
  for (std::size_t i = 0; i < series.t_s.size(); ++i) {
    const double t = series.t_s[i];
    if (std::abs(t - 3.0) < 0.005) confidence[i] = 0.2f;  // the second repetition's peak
    // The fourth's start at 6 s (the third ends there too, at a minimum equal to its start's,
    // the first of equals: its range keeps the confidence at 4 s).
    if (t > 5.5 && t < 6.5) confidence[i] = 0.3f;
    if (t > 7.2 && t < 7.8) confidence[i] = 0.0f;  // the fourth's descent: no extreme
  }
  const RepetitionSummary with = segment_repetitions(series.t_s, series.angle_deg, {}, confidence);
  const RepetitionSummary without = segment(series);
  ASSERT_EQ(with.count, 4);
  ASSERT_EQ(with.repetitions.size(), without.repetitions.size());
  for (std::size_t k = 0; k < with.repetitions.size(); ++k) {
    EXPECT_EQ(with.repetitions[k].t_start_s, without.repetitions[k].t_start_s);
    EXPECT_EQ(with.repetitions[k].t_end_s, without.repetitions[k].t_end_s);
    EXPECT_EQ(with.repetitions[k].range_deg, without.repetitions[k].range_deg);
    EXPECT_DOUBLE_EQ(without.repetitions[k].confidence, 1.0);
  }
  EXPECT_FLOAT_EQ(with.repetitions[0].confidence, 0.9f);
  EXPECT_FLOAT_EQ(with.repetitions[1].confidence, 0.2f);
  EXPECT_FLOAT_EQ(with.repetitions[2].confidence, 0.9f);
  EXPECT_FLOAT_EQ(with.repetitions[3].confidence, 0.3f);
  EXPECT_EQ(with.uncertain_count, 2);
  std::size_t confident = 0;
  for (const float c : confidence) confident += c >= kConfidentAt ? 1 : 0;
  EXPECT_DOUBLE_EQ(with.confident_fraction, static_cast<double>(confident) / static_cast<double>(confidence.size()));
  EXPECT_DOUBLE_EQ(without.confident_fraction, 1.0);
  EXPECT_EQ(without.uncertain_count, 0);
}

// The share of confident samples counts only the samples that have an angle, and a partial
// repetition's low confidence is reported but not counted as an uncertain repetition.
TEST(Repetitions, ConfidentFractionSkipsMissingSamplesAndPartialsAreNotUncertainCounts) {
  Series series = exercise(std::vector<Cycle>(2, Cycle{90, 2}));
  cut_after(series, 3.0);  // the second repetition is cut at its peak
  std::vector<float> confidence(series.t_s.size(), 1.0f);
  for (std::size_t i = 0; i < series.t_s.size(); ++i) {
    if (series.t_s[i] > 2.5) confidence[i] = 0.1f;
    if (series.t_s[i] > 0.45 && series.t_s[i] < 0.75) {
      series.angle_deg[i] = kNaN;  // missing (bridged: shorter than max_gap_s), its confidence 0 not counted
      confidence[i] = 0.0f;
    }
  }
  const RepetitionSummary summary = segment_repetitions(series.t_s, series.angle_deg, {}, confidence);
  ASSERT_EQ(summary.repetitions.size(), 2u);
  EXPECT_FALSE(summary.repetitions[0].partial);
  EXPECT_FLOAT_EQ(summary.repetitions[0].confidence, 1.0f);
  EXPECT_TRUE(summary.repetitions[1].partial);
  EXPECT_FLOAT_EQ(summary.repetitions[1].confidence, 0.1f);
  EXPECT_EQ(summary.uncertain_count, 0);
  std::size_t finite = 0, confident = 0;
  for (std::size_t i = 0; i < series.t_s.size(); ++i) {
    if (std::isnan(series.angle_deg[i])) continue;
    ++finite;
    confident += confidence[i] >= kConfidentAt ? 1 : 0;
  }
  EXPECT_LT(finite, series.t_s.size());
  EXPECT_DOUBLE_EQ(summary.confident_fraction, static_cast<double>(confident) / static_cast<double>(finite));
}

TEST(Repetitions, BadConfidencesAreRefusedNamingTheField) {
  const std::vector<double> t = {0.0, 0.1, 0.2, 0.3};
  const std::vector<double> a = {0.0, 10.0, 20.0, 10.0};
  expect_invalid([&] { segment_repetitions(t, a, {}, {1.0f, 1.0f}); }, "confidence", "has 2 samples but t_s has 4");
  expect_invalid(
      [&] {
        segment_repetitions(t, a, {}, {1.0f, 1.5f, 1.0f, 1.0f});
      },
      "confidence", "confidence[1] = 1.5 is not in [0, 1]");
  expect_invalid(
      [&] {
        segment_repetitions(t, a, {}, {1.0f, 1.0f, -0.5f, 1.0f});
      },
      "confidence", "confidence[2] = -0.5 is not in [0, 1]");
  expect_invalid(
      [&] {
        segment_repetitions(t, a, {}, {1.0f, 1.0f, 1.0f, std::nanf("")});
      },
      "confidence", "confidence[3] = nan is not in [0, 1]");
}

TEST(Repetitions, BadOptionsAreRefusedNamingTheOption) {
  const Series series = exercise({{90, 2}});
  const auto with = [&](const std::function<void(RepetitionOptions&)>& change) {
    RepetitionOptions options;
    change(options);
    return [series, options] { segment_repetitions(series.t_s, series.angle_deg, options); };
  };
  expect_invalid(with([](RepetitionOptions& o) { o.hysteresis_deg = -1; }), "repetition_options.hysteresis_deg",
                 "hysteresis_deg = -1 is not a positive");
  expect_invalid(with([](RepetitionOptions& o) { o.hysteresis_deg = 0; }), "repetition_options.hysteresis_deg",
                 "hysteresis_deg = 0");
  expect_invalid(with([](RepetitionOptions& o) { o.hysteresis_deg = kNaN; }), "repetition_options.hysteresis_deg",
                 "nan");
  expect_invalid(with([](RepetitionOptions& o) { o.min_amplitude_deg = 4; }), "repetition_options.min_amplitude_deg",
                 "min_amplitude_deg = 4 is not a finite angle of at least hysteresis_deg = 5");
  expect_invalid(with([](RepetitionOptions& o) { o.min_duration_s = -0.5; }), "repetition_options.min_duration_s",
                 "min_duration_s = -0.5");
  expect_invalid(with([](RepetitionOptions& o) {
                   o.min_duration_s = 5;
                   o.max_duration_s = 2;
                 }),
                 "repetition_options.max_duration_s", "max_duration_s = 2 is not at least min_duration_s = 5");
  expect_invalid(with([](RepetitionOptions& o) { o.max_gap_s = -1; }), "repetition_options.max_gap_s",
                 "max_gap_s = -1");
  expect_invalid(with([](RepetitionOptions& o) { o.max_gap_s = kNaN; }), "repetition_options.max_gap_s",
                 "max_gap_s = nan");

  // The edges that are allowed: min_amplitude equal to the hysteresis, no upper bound on duration
  // or gap.
  RepetitionOptions edges;
  edges.min_amplitude_deg = edges.hysteresis_deg;
  edges.max_duration_s = kInf;
  edges.max_gap_s = kInf;
  EXPECT_EQ(segment(series, edges).count, 1);
}

// A trunk tilt as the simulator scripts it: from upright to one side, held, over to the other
// side, held, back upright, held; each move a half-cosine ramp. Sampled at 100 Hz.
struct Tilt {
  double right_deg = 20, left_deg = -20;
};

void ramp_to(Series& series, double to_deg, double duration_s) {
  const double t0 = series.t_s.empty() ? -kDt : series.t_s.back();
  const double from_deg = series.angle_deg.empty() ? 0.0 : series.angle_deg.back();
  const int steps = static_cast<int>(std::lround(duration_s / kDt));
  for (int k = 1; k <= steps; ++k) {
    const double phase = static_cast<double>(k) / steps;
    series.t_s.push_back(t0 + k * kDt);
    series.angle_deg.push_back(from_deg + (to_deg - from_deg) * (1 - std::cos(kPi * phase)) / 2);
  }
}

void hold(Series& series, double duration_s) {
  ramp_to(series, series.angle_deg.empty() ? 0.0 : series.angle_deg.back(), duration_s);
}

Series tilts(const std::vector<Tilt>& cycles) {
  Series series;
  hold(series, 0.5);
  for (const Tilt& tilt : cycles) {
    ramp_to(series, tilt.right_deg, 1.5);
    hold(series, 0.5);
    ramp_to(series, tilt.left_deg, 3.0);
    hold(series, 0.5);
    ramp_to(series, 0.0, 1.5);
    hold(series, 0.5);
  }
  return series;
}

TEST(Repetitions, AnAngleSwingsAboutZeroWhenZeroIsInTheMiddleHalfOfItsMotion) {
  EXPECT_TRUE(swings_about_zero(tilts({{}, {}}).angle_deg));
  EXPECT_TRUE(swings_about_zero(tilts({{60, -30}}).angle_deg));  // zero at a third of the way
  EXPECT_FALSE(swings_about_zero(tilts({{60, -10}}).angle_deg));
  EXPECT_FALSE(swings_about_zero(exercise(std::vector<Cycle>(3, Cycle{90, 2})).angle_deg));
  EXPECT_FALSE(swings_about_zero({kNaN, 3.0}));
  EXPECT_FALSE(swings_about_zero({0.0, 0.0, 0.0}));
}

// Right, left, back upright: one repetition each, from leaving upright to coming back, with the
// whole arc as its range. Trough to trough (the rule for a rest at one end) would cut each at its
// left-most point and count one fewer.
TEST(Repetitions, ASwingToBothSidesOfZeroAndBackIsOneRepetition) {
  Series series = tilts({{}, {}, {}});
  std::mt19937 rng(5);
  std::uniform_real_distribution<double> noise(-2.0, 2.0);
  for (double& a : series.angle_deg) a += noise(rng);
  const RepetitionSummary summary = segment(series);
  ASSERT_EQ(summary.repetitions.size(), 3u);
  EXPECT_EQ(summary.count, 3);
  for (std::size_t k = 0; k < 3; ++k) {
    SCOPED_TRACE("repetition " + std::to_string(k));
    const Repetition& rep = summary.repetitions[k];
    EXPECT_FALSE(rep.partial);
    const double cycle_start_s = 0.5 + 7.5 * static_cast<double>(k);
    // It leaves rest (5 deg, the hysteresis) about 0.5 s into the 1.5 s ramp and comes back the
    // same time before the end of the last one.
    EXPECT_NEAR(rep.t_start_s, cycle_start_s + 0.5, 0.15);
    EXPECT_NEAR(rep.t_end_s, cycle_start_s + 7.0 - 0.5, 0.15);
    EXPECT_NEAR(rep.min_deg, -20, 2.1);
    EXPECT_NEAR(rep.max_deg, 20, 2.1);
    EXPECT_NEAR(rep.range_deg, 40, 4.1);
  }
}

// A fitted angle may rest off zero by more than the hysteresis (a pronation 13 deg off): the rest
// is where the series holds in the middle of its motion, so the repetitions are the same.
TEST(Repetitions, ASwingAboutZeroRestsWhereTheSeriesRestsNotAtZero) {
  Series series = tilts({{}, {}, {}});
  for (double& a : series.angle_deg) a -= 8;
  ASSERT_TRUE(swings_about_zero(series.angle_deg));
  const RepetitionSummary summary = segment(series);
  ASSERT_EQ(summary.repetitions.size(), 3u);
  EXPECT_EQ(summary.count, 3);
  for (const Repetition& rep : summary.repetitions) {
    EXPECT_NEAR(rep.min_deg, -28, 0.1);
    EXPECT_NEAR(rep.max_deg, 12, 0.1);
  }
}

// A rest at zero between the two sides (a forearm rolled into pronation, back to neutral, then
// into supination) is inside the repetition: it ends only once both sides have been visited.
TEST(Repetitions, ARestBetweenTheTwoSidesIsInsideTheRepetition) {
  Series series;
  hold(series, 0.5);
  for (int k = 0; k < 2; ++k) {
    ramp_to(series, 60, 1.0);
    ramp_to(series, 0, 1.0);
    hold(series, 1.0);
    ramp_to(series, -60, 1.0);
    ramp_to(series, 0, 1.0);
    hold(series, 1.0);
  }
  const RepetitionSummary summary = segment(series);
  EXPECT_EQ(summary.count, 2);
  ASSERT_EQ(summary.repetitions.size(), 2u);
  EXPECT_NEAR(summary.repetitions[0].range_deg, 120, 0.5);
  EXPECT_GT(summary.repetitions[0].duration_s, 4.0);
}

// Motion cut by the start or the end of the series is partial; a swing whose whole arc is below
// the minimum amplitude is partial too.
TEST(Repetitions, ASwingAboutZeroCutOrTooSmallIsPartial) {
  Series series = tilts({{}, {}, {8, -8}, {}});
  const RepetitionSummary whole = segment(series);
  ASSERT_EQ(whole.repetitions.size(), 4u);
  EXPECT_EQ(whole.count, 3);
  EXPECT_TRUE(whole.repetitions[2].partial);  // 16 deg of arc, under 20
  EXPECT_NEAR(whole.repetitions[2].range_deg, 16, 0.1);

  // Start in the middle of the first swing and stop in the middle of the last one.
  Series cut;
  for (std::size_t i = 0; i < series.t_s.size(); ++i) {
    if (series.t_s[i] < 2.5 || series.t_s[i] > 26.0) continue;
    cut.t_s.push_back(series.t_s[i]);
    cut.angle_deg.push_back(series.angle_deg[i]);
  }
  const RepetitionSummary summary = segment(cut);
  ASSERT_EQ(summary.repetitions.size(), 4u);
  EXPECT_TRUE(summary.repetitions.front().partial);
  EXPECT_TRUE(summary.repetitions.back().partial);
  EXPECT_EQ(summary.count, 1);  // the second; the third is too small
}

// About zero the same: tilts of 8 deg each way, 16 deg of arc, count when they are the series'
// whole motion (beside 20 deg tilts they are partial: ASwingAboutZeroCutOrTooSmallIsPartial).
TEST(Repetitions, SmallSwingsAboutZeroCountWhenTheyAreTheWholeMotion) {
  const RepetitionSummary tilted = segment(tilts({{8, -8}, {8, -8}, {8, -8}}));
  EXPECT_EQ(tilted.count, 3);
  EXPECT_NEAR(tilted.mean_range_deg, 16.0, 0.1);
}

// Forearm rolls as a fit gives them: the series starts 24 deg to one side of rest (pronation is
// defined only once the elbow bends), settles to rest, and the rolls then go the other way first
// (`first_roll_deg` negative: the way the start came from) or not.
Series settled_start_then_rolls(double first_roll_deg) {
  Series series{{0.0}, {-24.0}};
  ramp_to(series, 0, 0.3);
  hold(series, 1.0);
  for (int k = 0; k < 3; ++k) {
    ramp_to(series, first_roll_deg, 1.0);
    ramp_to(series, -first_roll_deg, 2.0);
    ramp_to(series, 0, 1.0);
    hold(series, 0.5);
  }
  return series;
}

// A start out of rest that settles, followed by a roll to the same side: the start cannot be on
// its way across (it would have gone on to the other side), so it ends where it came back to rest
// and is partial on its own; all three rolls count.
TEST(Repetitions, AStartOutOfRestThatSettlesBeforeASwingTheSameWayIsPartialOnItsOwn) {
  Series series = settled_start_then_rolls(-60);
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> noise(-2.0, 2.0);
  for (double& a : series.angle_deg) a += noise(rng);
  ASSERT_TRUE(swings_about_zero(series.angle_deg));
  const RepetitionSummary summary = segment(series);
  ASSERT_EQ(summary.repetitions.size(), 4u);
  EXPECT_EQ(summary.count, 3);
  const Repetition& start = summary.repetitions[0];
  EXPECT_TRUE(start.partial);
  EXPECT_NEAR(start.min_deg, -24, 2.1);
  EXPECT_LT(start.t_end_s, 0.35);  // where it came back within the hysteresis, not at the roll
  for (std::size_t k = 1; k < 4; ++k) {
    SCOPED_TRACE("roll " + std::to_string(k));
    const Repetition& roll = summary.repetitions[k];
    EXPECT_FALSE(roll.partial);
    EXPECT_NEAR(roll.range_deg, 120, 4.1);
    // Each leaves rest about a third of the way into its first 1 s ramp.
    EXPECT_NEAR(roll.t_start_s, 1.3 + 4.5 * static_cast<double>(k - 1) + 0.3, 0.15);
  }
}

// The same start before a roll the other way cannot be told from a slow roll crossing the rest,
// so it stays joined to the first roll up to that roll's crossing, as a partial repetition; the
// rolls after it are counted from crossing to crossing, one fewer (docs/measures.md, "Angles that
// swing about their zero"). That partial says it may hold a repetition; nothing else does.
TEST(Repetitions, AStartOutOfRestThatSettlesBeforeASwingTheOtherWayStaysJoinedToIt) {
  const RepetitionSummary summary = segment(settled_start_then_rolls(60));
  ASSERT_EQ(summary.repetitions.size(), 4u);
  EXPECT_EQ(summary.count, 2);
  const Repetition& start = summary.repetitions[0];
  EXPECT_TRUE(start.partial);
  EXPECT_TRUE(start.may_hold_repetition);
  EXPECT_NEAR(start.t_start_s, 0.0, 1e-9);
  EXPECT_NEAR(start.max_deg, 60, 0.1);
  EXPECT_GT(start.t_end_s, 3.0);  // in the first roll's crossing, on its way to -60
  for (std::size_t k = 1; k < 4; ++k) EXPECT_FALSE(summary.repetitions[k].may_hold_repetition) << k;
  EXPECT_TRUE(summary.repetitions[3].partial);
}

// A swing already under way when the recording starts, crossing the rest without stopping, is
// marked as well (the two look the same at 100 Hz: samples within the hysteresis of rest as it
// crosses); a series that starts at rest and one whose start settles before a swing the same way
// are not.
TEST(Repetitions, AStartOutOfRestThatCrossesMayHoldARepetitionWhetherItSettledOrNot) {
  Series under_way{{0.0}, {-40.0}};  // out on one side from the first sample
  ramp_to(under_way, 40, 2.0);       // across the rest without stopping
  ramp_to(under_way, 0, 1.0);
  hold(under_way, 0.5);
  const RepetitionSummary crossing = segment(under_way);
  ASSERT_EQ(crossing.repetitions.size(), 1u);
  EXPECT_TRUE(crossing.repetitions[0].partial);
  EXPECT_TRUE(crossing.repetitions[0].may_hold_repetition);
  for (const Series& series : {tilts({{}, {}}), settled_start_then_rolls(-60)}) {
    const RepetitionSummary summary = segment(series);
    ASSERT_FALSE(summary.repetitions.empty());
    for (const Repetition& rep : summary.repetitions) EXPECT_FALSE(rep.may_hold_repetition);
  }
}

// Rolls back to back at 30 Hz, fast enough that the sample after each return to rest is already
// out of the hysteresis band, after a start out of rest: every roll after the start leaves from
// where the last one came back, not from the start of the series.
TEST(Repetitions, BackToBackSwingsAfterAStartOutOfRestEachStartWhereTheLastEnded) {
  Series series;
  const double dt = 1.0 / 30;
  const auto add = [&](double deg) {
    series.t_s.push_back(series.t_s.empty() ? 0.0 : series.t_s.back() + dt);
    series.angle_deg.push_back(deg);
  };
  for (int k = 0; k < 9; ++k) add(9.0);   // out of rest to one side
  for (int k = 0; k < 40; ++k) add(0.0);  // settled
  const double period_s = 1.2;
  const int per_roll = static_cast<int>(std::lround(period_s / dt));
  for (int k = 1; k <= 3 * per_roll; ++k) add(60 * std::sin(2 * kPi * k * dt / period_s));
  for (int k = 0; k < 30; ++k) add(0.0);
  const RepetitionSummary summary = segment(series);
  ASSERT_EQ(summary.repetitions.size(), 4u);
  EXPECT_TRUE(summary.repetitions[0].partial);
  EXPECT_EQ(summary.count, 3);
  for (std::size_t k = 1; k + 1 < summary.repetitions.size(); ++k) {
    EXPECT_NEAR(summary.repetitions[k + 1].t_start_s, summary.repetitions[k].t_end_s, 1e-9) << k;
  }
}

// Back at rest after one side, leaving again takes a real move (the hysteresis) from where the
// angle came closest to rest, as between repetitions: a fit's jolt 5.3 deg past rest, 5.8 deg from
// where the trunk had settled, is not the other side, and the repetition runs on through the
// real tilt to the left.
TEST(Repetitions, AJoltPastRestAfterOneSideIsNotTheOtherSide) {
  Series series;
  hold(series, 0.5);
  ramp_to(series, 20, 1.5);
  hold(series, 0.5);
  ramp_to(series, 0.5, 1.5);
  series.t_s.push_back(series.t_s.back() + kDt);
  series.angle_deg.push_back(-5.3);
  ramp_to(series, 0, 0.2);
  hold(series, 0.5);
  ramp_to(series, -20, 1.5);
  hold(series, 0.5);
  ramp_to(series, 0, 1.5);
  hold(series, 0.5);
  const RepetitionSummary summary = segment(series);
  ASSERT_EQ(summary.repetitions.size(), 1u);
  EXPECT_EQ(summary.count, 1);
  EXPECT_NEAR(summary.repetitions[0].range_deg, 40, 0.1);
}

// Mid-session, a move to one side and back, then a whole swing that starts out to that same
// side: the first is partial on its own (a repetition goes out to both sides), the swing counts.
TEST(Repetitions, AnExcursionToOneSideAndBackIsPartialWhenTheNextLeavesTheSameWay) {
  Series series;
  hold(series, 0.5);
  ramp_to(series, 30, 1.0);
  ramp_to(series, 0, 1.0);
  hold(series, 1.0);
  ramp_to(series, 30, 1.0);
  ramp_to(series, -30, 2.0);
  ramp_to(series, 0, 1.0);
  hold(series, 0.5);
  const RepetitionSummary summary = segment(series);
  ASSERT_EQ(summary.repetitions.size(), 2u);
  EXPECT_EQ(summary.count, 1);
  EXPECT_TRUE(summary.repetitions[0].partial);
  EXPECT_NEAR(summary.repetitions[0].range_deg, 30, 5.1);
  EXPECT_FALSE(summary.repetitions[1].partial);
  EXPECT_NEAR(summary.repetitions[1].range_deg, 60, 0.1);
}

// The exercise's joint is the one whose angle moves most; a still joint with noise loses to it,
// missing samples are ignored.
TEST(DominantSeries, PicksTheSeriesThatMoves) {
  Series moving = exercise(std::vector<Cycle>(3, Cycle{90, 2}));
  moving.angle_deg[10] = kNaN;
  std::vector<double> still(moving.angle_deg.size(), 40.0);
  std::vector<double> small(moving.angle_deg.size());
  std::mt19937 rng(3);
  std::uniform_real_distribution<double> noise(-3.0, 3.0);
  for (double& a : still) a += noise(rng);
  for (std::size_t i = 0; i < small.size(); ++i) small[i] = 20 + 0.2 * moving.angle_deg[i];
  EXPECT_EQ(dominant_series({still, moving.angle_deg, small}), 1);
  EXPECT_EQ(dominant_series({moving.angle_deg, still}), 0);
  EXPECT_EQ(dominant_series({still, small}), 1);
}

// The spread is between the 5th and 95th percentiles: a few outliers (under 5% of the samples)
// do not make a still joint dominant; more than 5% of them do.
TEST(DominantSeries, OutliersBelowFivePercentDoNotCount) {
  std::vector<double> ramp(101);
  for (int i = 0; i <= 100; ++i) ramp[i] = i;  // 5th-95th: 5 to 95
  std::vector<double> few_glitches(101, 0.0), many_glitches(101, 0.0);
  for (int i = 0; i < 4; ++i) few_glitches[i * 25] = 1000;   // 4 of 101: the 95th is still 0
  for (int i = 0; i < 6; ++i) many_glitches[i * 16] = 1000;  // 6 of 101: the 95th is 1000
  EXPECT_EQ(dominant_series({few_glitches, ramp}), 1);
  EXPECT_EQ(dominant_series({many_glitches, ramp}), 0);
}

TEST(DominantSeries, AnAngleDefinedInFewFramesDoesNotCompete) {
  // Elevation swinging 10-150 deg in every frame; pronation defined in 9 of 600 frames, scattered
  // over +-110 deg (a nearly straight elbow crossing the flexion bound for a moment).
  std::vector<double> elevation, pronation(600, kNaN);
  for (int i = 0; i < 600; ++i) elevation.push_back(80 - 70 * std::cos(2 * std::numbers::pi * i / 200));
  for (int i = 0; i < 9; ++i) pronation[static_cast<std::size_t>(60 * i + 7)] = (i % 2 ? 110.0 : -110.0) + i;
  EXPECT_EQ(dominant_series({pronation, elevation}), 1);
  // Defined in half the frames it competes again, and its 220 deg spread wins.
  for (std::size_t i = 0; i < 600; i += 2) pronation[i] = (i % 4 ? 110.0 : -110.0);
  EXPECT_EQ(dominant_series({pronation, elevation}), 0);
}

// A trunk tilting +-18 deg at full confidence against a fitted elbow flexion that scatters over
// 150 deg at confidence 0.1 (near full extension, its arm lengths uncertain): the tilt is the
// exercise. Unsure angles still compete when nothing confident moves enough to make a repetition
// (pronation at confidence ~0 in forearm rolling, the elbow held still), and a series that is
// confident in just half of its frames counts as confident.
TEST(DominantSeries, AnUnsureAngleGivesWayToAConfidentOneThatMovesEnough) {
  const Series tilt_series = tilts({{18, -18}, {18, -18}});
  const std::vector<double>& tilt = tilt_series.angle_deg;
  const std::size_t n = tilt.size();
  std::vector<double> elbow(n), still(n);
  std::mt19937 rng(11);
  std::uniform_real_distribution<double> scatter(0.0, 150.0), noise(-2.0, 2.0);
  for (std::size_t i = 0; i < n; ++i) {
    elbow[i] = scatter(rng);
    still[i] = 90 + noise(rng);
  }
  const std::vector<float> sure(n, 1.0f), unsure(n, 0.1f);
  EXPECT_EQ(dominant_series({elbow, tilt}), 0);  // without confidences the spread decides
  EXPECT_EQ(dominant_series({elbow, tilt}, {unsure, sure}, 20.0), 1);
  // A confident angle that moves less than the minimum amplitude leaves the choice to spread.
  EXPECT_EQ(dominant_series({elbow, still}, {unsure, sure}, 20.0), 0);
  EXPECT_EQ(dominant_series({elbow, tilt}, {unsure, sure}, 40.0), 0);
  // Half of the frames confident is confident; just under half is not.
  const std::size_t half_n = (n + 1) / 2;
  std::vector<float> half(n, 0.0f), under_half(n, 0.0f);
  std::fill_n(half.begin(), half_n, 0.5f);
  std::fill_n(under_half.begin(), half_n - 1, 0.5f);
  EXPECT_EQ(dominant_series({elbow, tilt}, {half, sure}, 20.0), 0);
  EXPECT_EQ(dominant_series({elbow, tilt}, {under_half, sure}, 20.0), 1);
}

TEST(DominantSeries, ConfidencesThatDoNotPairUpAreRefused) {
  const std::vector<double> a{1.0, 2.0, 3.0}, b{4.0, 5.0, 6.0};
  expect_invalid(
      [&] {
        dominant_series({a, b}, {{1, 1, 1}}, 20.0);
      },
      "confidence", "has 1 series but angle_series_deg has 2");
  expect_invalid(
      [&] {
        dominant_series({a, b}, {{1, 1, 1}, {1, 1}}, 20.0);
      },
      "confidence", "has 2 samples but angle_series_deg[1] has 3");
  expect_invalid(
      [&] {
        dominant_series({a, b}, {{1, 1, 1}, {1, 2, 1}}, 20.0);
      },
      "confidence", "confidence[1] = 2 is not in [0, 1]");
}

TEST(DominantSeries, NoneWithoutTwoFiniteSamples) {
  EXPECT_EQ(dominant_series({}), -1);
  EXPECT_EQ(dominant_series({{}, {kNaN, kNaN, kNaN}, {5.0}, {kNaN, 7.0, kInf}}), -1);
  // Two finite samples are enough, even if they do not move; the first of equals wins.
  EXPECT_EQ(dominant_series({{kNaN}, {1.0, 1.0}, {2.0, 2.0}}), 1);
}

}  // namespace
}  // namespace posefuse::measures
