// The whole-session simulator's truth is consistent: the IMU (moved by the scripted arm chain)
// sits on the strap of the rendered body's forearm, frames map as documented, and the strap
// slip stays within its bounds.
#include <gtest/gtest.h>

#include <cstdio>

#include "common/error.hpp"
#include "geometry/quaternion.hpp"
#include "session/session_validator.hpp"
#include "sim/sim_session.hpp"
#include "test_camera.hpp"

using namespace posefuse;
using namespace posefuse::sim;

namespace {

class ValidatingSink : public session::ChunkSink {
 public:
  void write(const session::SessionChunk& chunk) override { validator.check(chunk); }
  void finish() override {}
  session::SessionValidator validator;
};

SimSessionOptions small(bool slip) {
  SimSessionOptions o;
  o.duration_s = 2.0;
  o.depth_intrinsics = sim::testing::quarter_kinect_intrinsics();
  o.color = false;
  o.strap_slip.enabled = slip;
  o.mount_sigma_rad = 0.0;
  return o;
}

double angle_deg(const Quat& a, const Quat& b) { return geometry::angle_between(a, b) * 180.0 / 3.14159265358979; }

}  // namespace

TEST(SimSessionTruth, ImuSitsOnTheRenderedStrap) {
  const SimSessionOptions o = small(false);
  ValidatingSink sink;
  const SimTruth truth = simulate_session(o, sink);
  sink.validator.finish();
  ASSERT_EQ(truth.frames.size(), 61u);
  ASSERT_EQ(truth.devices.size(), 3u);
  double worst_mm = 0, worst_deg = 0;
  for (const SimFrameTruth& frame : truth.frames) {
    for (int arm = 0; arm < 2; ++arm) {
      const auto a = static_cast<std::size_t>(arm);
      const Vec3 x_F = frame.K_from_F[a] * Vec3::UnitX();
      const Vec3 expected_imu = frame.strap_p_K[a] + o.strap_radius_m * x_F;
      worst_mm = std::max(worst_mm, 1e3 * (frame.imu_p_K[a] - expected_imu).norm());
      worst_deg = std::max(worst_deg, angle_deg(frame.K_from_imu[a], frame.K_from_F[a]));  // F_from_A = I
      EXPECT_NEAR(frame.pronation_rad[a], 0.0, 1e-9);  // arm raising does not roll the forearm
      EXPECT_GE(frame.forearm_visible_fraction[a], 0.8) << frame.t_us;
    }
    // The base IMU is fixed on the camera.
    EXPECT_LT(angle_deg(frame.K_from_imu[2], truth.K_from_B), 1e-6);
  }
  std::printf("IMU vs rendered strap: worst %.4f mm, %.5f deg\n", worst_mm, worst_deg);
  EXPECT_LT(worst_mm, 1.0);
  EXPECT_LT(worst_deg, 0.05);
  // The camera is level: W's up is K's up.
  EXPECT_LT((truth.K_from_W * Vec3::UnitZ() - Vec3::UnitY()).norm(), 1e-12);
  // Devices: arm IMUs then the base, with their roles.
  EXPECT_EQ(truth.devices[0].role, v1::ImuDevice::ARM_LEFT);
  EXPECT_EQ(truth.devices[1].role, v1::ImuDevice::ARM_RIGHT);
  EXPECT_EQ(truth.devices[2].role, v1::ImuDevice::BASE);
  EXPECT_GT(truth.buzzer_heard_camera_s, truth.buzzer_stop_camera_s);
}

TEST(SimSessionTruth, StrapSlipStaysWithinItsBounds) {
  const SimSessionOptions o = small(true);
  ValidatingSink sink;
  const SimTruth truth = simulate_session(o, sink);
  double worst_mm = 0, worst_deg = 0;
  for (const SimFrameTruth& frame : truth.frames) {
    for (std::size_t a = 0; a < 2; ++a) {
      const Vec3 expected_imu = frame.strap_p_K[a] + o.strap_radius_m * (frame.K_from_F[a] * Vec3::UnitX());
      worst_mm = std::max(worst_mm, 1e3 * (frame.imu_p_K[a] - expected_imu).norm());
      worst_deg = std::max(worst_deg, angle_deg(frame.K_from_imu[a], frame.K_from_F[a]));
    }
  }
  const double bound_mm = 1e3 * (o.strap_slip.max_slide_m + o.strap_radius_m * o.strap_slip.max_rotation_rad) + 1.0;
  std::printf("with slip: worst %.3f mm (bound %.3f), %.3f deg\n", worst_mm, bound_mm, worst_deg);
  EXPECT_GT(worst_mm, 0.2);  // it does slip
  EXPECT_LT(worst_mm, bound_mm);
  EXPECT_GT(worst_deg, 0.05);
  EXPECT_LT(worst_deg, o.strap_slip.max_rotation_rad * 180 / 3.14159265358979 + 0.05);
}

TEST(SimSessionTruth, BadOptionsNameTheField) {
  const auto field_of = [](SimSessionOptions o) {
    ValidatingSink sink;
    try {
      simulate_session(o, sink);
    } catch (const Error& e) {
      return e.field();
    }
    return std::string("no error");
  };
  SimSessionOptions o = small(false);
  o.duration_s = 0.5;
  EXPECT_EQ(field_of(o), "duration_s");
  o = small(false);
  o.strap_to_elbow_m = 0.3;
  EXPECT_EQ(field_of(o), "strap_to_elbow_m");
  o = small(false);
  o.wall_distance_m = 2.6;
  EXPECT_EQ(field_of(o), "wall_distance_m");
  o = small(false);
  o.motion = "juggling";
  EXPECT_EQ(field_of(o), "motion");
  o = small(false);
  o.threads = 0;
  EXPECT_EQ(field_of(o), "threads");
  o = small(false);
  o.betas = Eigen::VectorXd::Constant(3, std::nan(""));
  EXPECT_EQ(field_of(o), "betas");
}
