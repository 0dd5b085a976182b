// The forearm stage in the pipeline on a synthetic session (tests/session/forearm_session.hpp):
// calibration, orientation and pronation per IMU sample, IMU position per frame, a gap's live
// estimate and recovered segments, and clear warnings for sessions it cannot use.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <map>
#include <numbers>

#include "forearm/forearm_orientation.hpp"
#include "forearm_session.hpp"
#include "session/pipeline.hpp"
#include "session/stages/default_stages.hpp"

namespace posefuse::session {
namespace {

using forearm::Quat;
using forearm::Vec3;
using testing::ForearmSessionOptions;
using testing::ForearmSessionTruth;
constexpr double kDeg = std::numbers::pi / 180.0;

struct Sink : ResultSink {
  void emit(v1::FitResult&& result) override { results.push_back(std::move(result)); }
  std::vector<v1::FitResult> results;
  std::vector<v1::Warning> warnings() const {
    std::vector<v1::Warning> out;
    for (const auto& r : results) {
      if (r.has_warning()) out.push_back(r.warning());
    }
    return out;
  }
};

struct StageRun {
  ForearmSessionTruth truth;
  Sink sink;
};

// One pipeline run per options, shared by the tests that read it.
const StageRun& run_session(const ForearmSessionOptions& options) {
  static std::map<std::string, std::unique_ptr<StageRun>> cache;
  const std::string key = std::to_string(options.strap_drawn) + std::to_string(options.buzzer) +
                          std::to_string(options.camera_alignment) + std::to_string(options.hold_s);
  auto& slot = cache[key];
  if (!slot) {
    slot = std::make_unique<StageRun>();
    const auto chunks = testing::make_forearm_session(options, &slot->truth);
    SessionPipeline pipeline(make_default_stages(), slot->sink);
    for (const auto& chunk : chunks) pipeline.push(chunk);
    pipeline.close();
  }
  return *slot;
}

Vec3 vec(const v1::Vec3& v) { return {v.x(), v.y(), v.z()}; }
Quat quat(const v1::Quaternion& q) { return Quat(q.w(), q.x(), q.y(), q.z()); }

std::size_t frame_index(const ForearmSessionTruth& truth, std::int64_t t_us) {
  const auto it = std::lower_bound(truth.frame_t_us.begin(), truth.frame_t_us.end(), t_us);
  return static_cast<std::size_t>(it - truth.frame_t_us.begin());
}

TEST(ForearmStage, CalibratesTheForearmModel) {
  const StageRun& r = run_session({});
  for (const auto& w : r.sink.warnings()) ADD_FAILURE() << w.code() << " " << w.field() << ": " << w.message();
  const auto calibration = std::find_if(r.sink.results.begin(), r.sink.results.end(),
                                        [](const v1::FitResult& x) { return x.has_calibration(); });
  ASSERT_NE(calibration, r.sink.results.end());
  ASSERT_EQ(calibration->calibration().forearms_size(), 1);
  const v1::ForearmModel& model = calibration->calibration().forearms(0);
  EXPECT_TRUE(model.estimated());
  EXPECT_EQ(model.device_id(), "arm_r");
  EXPECT_EQ(model.arm(), v1::RIGHT);
  EXPECT_GE(model.calibration_frames(), 80u);  // the 3 s hold at 30 Hz
  // Joint noise 4 mm averaged over the hold; a colour pixel is 5 mm, a depth pixel 14 mm here.
  std::printf("calibration: r %.4f (true %.4f) d_se %.4f (%.4f) d_sw %.4f (%.4f) d_ul %.4f (%.4f) m, A_from_F %.2f deg\n",
              model.r_m(), r.truth.model.r_m, model.d_se_m(), r.truth.model.d_se_m, model.d_sw_m(),
              r.truth.model.d_sw_m, model.d_ul_m(), r.truth.model.d_ul_m,
              geometry::angle_between(quat(model.a_from_f()), r.truth.model.F_from_A.conjugate()) / kDeg);
  EXPECT_NEAR(model.r_m(), r.truth.model.r_m, 0.006);
  EXPECT_NEAR(model.d_se_m(), r.truth.model.d_se_m, 0.006);
  EXPECT_NEAR(model.d_sw_m(), r.truth.model.d_sw_m, 0.006);
  EXPECT_NEAR(model.d_ul_m(), r.truth.model.d_ul_m, 0.003);
  const Quat A_from_F = quat(model.a_from_f());
  EXPECT_LT(geometry::angle_between(A_from_F, r.truth.model.F_from_A.conjugate()), 2.0 * kDeg);
  // Clocks: offsets reported for both IMUs with a sub-millisecond uncertainty.
  EXPECT_EQ(calibration->calibration().clock_offset_us_size(), 2);
  EXPECT_LT(calibration->calibration().clock_offset_sigma_us().at("arm_r"), 1000.0);
  EXPECT_LT(geometry::angle_between(quat(calibration->calibration().k_from_w()), r.truth.K_from_W), 1.0 * kDeg);
}

TEST(ForearmStage, OrientationAndPronationForEveryImuSample) {
  const StageRun& r = run_session({});
  std::size_t samples = 0;
  double sum_sq = 0.0, max_error = 0.0, pronation_max_error = 0.0;
  for (const auto& result : r.sink.results) {
    if (!result.has_forearm_orientations()) continue;
    const v1::ForearmOrientationBatch& b = result.forearm_orientations();
    EXPECT_EQ(b.device_id(), "arm_r");
    ASSERT_EQ(b.k_from_f_size(), 4 * b.t_us_size());
    for (int i = 0; i < b.t_us_size(); ++i) {
      // Truth at the nearest camera frame (IMU samples are within 6 ms of one; the forearm
      // turns at most ~1.5 rad/s here, so compare only samples within 2 ms of a frame).
      const std::size_t k = frame_index(r.truth, b.t_us(i) - 2000);
      if (k >= r.truth.frame_t_us.size() || std::abs(r.truth.frame_t_us[k] - b.t_us(i)) > 2000) continue;
      const Quat K_from_F(b.k_from_f(4 * i), b.k_from_f(4 * i + 1), b.k_from_f(4 * i + 2), b.k_from_f(4 * i + 3));
      const double e = geometry::angle_between(K_from_F, r.truth.K_from_F[k]);
      sum_sq += e * e;
      max_error = std::max(max_error, e);
      const double true_pronation =
          forearm::pronation_angle(r.truth.K_from_F_calibration, r.truth.K_from_F[k], forearm::Side::kRight);
      pronation_max_error = std::max(pronation_max_error, std::abs(b.pronation_rad(i) - true_pronation));
      ++samples;
    }
  }
  ASSERT_GT(samples, 50u);
  const double rms = std::sqrt(sum_sq / samples);
  std::printf("forearm orientation: %zu samples, RMS %.2f deg, max %.2f deg; pronation max error %.2f deg\n", samples,
              rms / kDeg, max_error / kDeg, pronation_max_error / kDeg);
  // Filter noise, the 2 ms time offset and the calibration's eq. 9 error (< 2 degrees).
  EXPECT_LT(rms, 3.0 * kDeg) << "RMS " << rms / kDeg << " deg over " << samples;
  EXPECT_LT(max_error, 6.0 * kDeg);
  EXPECT_LT(pronation_max_error, 6.0 * kDeg);
}

TEST(ForearmStage, ImuPositionsVisibleThenPredictedThenRecovered) {
  const ForearmSessionOptions options;
  const StageRun& r = run_session(options);
  double visible_sq = 0.0;
  std::size_t visible = 0, predicted = 0, frames = 0;
  double predicted_max = 0.0;
  for (const auto& result : r.sink.results) {
    if (!result.has_frame()) continue;
    ++frames;
    const std::size_t k = frame_index(r.truth, result.frame().t_us());
    ASSERT_LT(k, r.truth.frame_t_us.size());
    ASSERT_EQ(result.frame().forearms_size(), 1);
    for (const v1::ImuPosition& p : result.frame().imu_positions()) {
      const double e = (vec(p.position_m()) - r.truth.imu_K[k]).norm();
      if (p.source() == v1::VISUAL) {
        visible_sq += e * e;
        ++visible;
      } else {
        EXPECT_EQ(p.source(), v1::PREDICTED);
        const double t = r.truth.frame_t_us[k] * 1e-6;
        EXPECT_GE(t, options.occlusion_begin_s);
        EXPECT_LT(t, options.occlusion_end_s);
        predicted_max = std::max(predicted_max, e);
        ++predicted;
      }
    }
  }
  EXPECT_EQ(frames, r.truth.frame_t_us.size());
  EXPECT_GT(visible, frames / 2);
  EXPECT_GE(predicted, 20u);  // the 0.9 s occlusion at 30 Hz
  EXPECT_LT(std::sqrt(visible_sq / visible), 0.012) << "visible RMS";
  EXPECT_LT(predicted_max, 0.15) << "live estimate max";

  std::map<v1::RecoveredSegment::Method, double> max_error;
  for (const auto& result : r.sink.results) {
    if (!result.has_recovered_segment()) continue;
    const v1::RecoveredSegment& s = result.recovered_segment();
    EXPECT_EQ(s.device_id(), "arm_r");
    double worst = 0.0;
    for (const auto& sample : s.samples()) {
      const std::size_t k = frame_index(r.truth, sample.t_us() - 20000);
      // Truth only at camera frames: compare the samples within 2 ms of one.
      for (std::size_t j = k; j < std::min(k + 3, r.truth.frame_t_us.size()); ++j) {
        if (std::abs(r.truth.frame_t_us[j] - sample.t_us()) <= 2000) {
          worst = std::max(worst, (vec(sample.imu_m()) - r.truth.imu_K[j]).norm());
        }
      }
    }
    max_error[s.method()] = std::max(max_error[s.method()], worst);
  }
  ASSERT_EQ(max_error.size(), 2u) << "one segment per method";
  std::printf("IMU position: visible %zu frames RMS %.1f mm; predicted %zu frames max %.1f mm; recovered max: "
              "smoother %.1f mm, paper %.1f mm\n", visible, 1e3 * std::sqrt(visible_sq / visible), predicted,
              1e3 * predicted_max, 1e3 * max_error[v1::RecoveredSegment::SMOOTHER],
              1e3 * max_error[v1::RecoveredSegment::PAPER]);
  EXPECT_LT(max_error[v1::RecoveredSegment::SMOOTHER], 0.04);
  EXPECT_LT(max_error[v1::RecoveredSegment::PAPER], 0.08);
  EXPECT_EQ(r.sink.results.back().summary().recovered_segments(), 2u);
}

bool has_warning(const StageRun& r, const std::string& code, const std::string& field_part, const std::string& text) {
  for (const auto& w : r.sink.warnings()) {
    if (w.code() == code && w.field().find(field_part) != std::string::npos &&
        w.message().find(text) != std::string::npos) {
      return true;
    }
  }
  return false;
}

std::size_t count(const StageRun& r, v1::FitResult::ResultCase kind) {
  return static_cast<std::size_t>(std::count_if(r.sink.results.begin(), r.sink.results.end(),
                                                [&](const v1::FitResult& x) { return x.result_case() == kind; }));
}

TEST(ForearmStage, NoBuzzerEventIsNamed) {
  ForearmSessionOptions options;
  options.buzzer = false;
  const StageRun& r = run_session(options);
  EXPECT_TRUE(has_warning(r, "FOREARM_NO_SYNC", "sync_event", "no BUZZER_STOP event"));
  EXPECT_EQ(count(r, v1::FitResult::kForearmOrientations), 0u);
  EXPECT_EQ(count(r, v1::FitResult::kFrame), 0u);
  EXPECT_GT(count(r, v1::FitResult::kImuOrientations), 0u);  // the IMU stage is unaffected
}

TEST(ForearmStage, TooShortCalibrationIsNamed) {
  ForearmSessionOptions options;
  options.hold_s = -1.0;  // already moving at full speed at t = 0: no 15-frame still run
  const StageRun& r = run_session(options);
  EXPECT_TRUE(has_warning(r, "FOREARM_CALIBRATION", "forearm[arm_r].calibration", "held still for"));
  EXPECT_EQ(count(r, v1::FitResult::kForearmOrientations), 0u);
}

TEST(ForearmStage, StrapNeverSeenGivesOrientationOnly) {
  ForearmSessionOptions options;
  options.strap_drawn = false;
  const StageRun& r = run_session(options);
  EXPECT_TRUE(has_warning(r, "FOREARM_STRAP_NOT_SEEN", "forearm[arm_r].strap", "seen in 0 of"));
  EXPECT_GT(count(r, v1::FitResult::kForearmOrientations), 0u);
  for (const auto& result : r.sink.results) {
    if (result.has_frame()) {
      EXPECT_EQ(result.frame().imu_positions_size(), 0);
    }
  }
  EXPECT_EQ(count(r, v1::FitResult::kRecoveredSegment), 0u);
}

TEST(ForearmStage, NoCameraAlignmentIsNamed) {
  ForearmSessionOptions options;
  options.camera_alignment = false;
  const StageRun& r = run_session(options);
  EXPECT_TRUE(has_warning(r, "FOREARM_NO_CAMERA_ALIGNMENT", "header.options[forearm.K_from_B]", "eq. 8"));
  EXPECT_EQ(count(r, v1::FitResult::kFrame), 0u);
}

}  // namespace
}  // namespace posefuse::session
