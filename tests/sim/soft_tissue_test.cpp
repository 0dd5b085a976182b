// Soft-tissue wobble (soft_tissue.hpp): none without acceleration, bounded, ringing down after a
// stop; on the mesh only where flesh is loose; the session's IMU and joint truth never see it.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <numbers>

#include "body/smpl_model.hpp"
#include "body/template_generator.hpp"
#include "common/error.hpp"
#include "session/image_codec.hpp"
#include "sim/render_model.hpp"
#include "sim/sim_session.hpp"
#include "sim/soft_tissue.hpp"
#include "test_camera.hpp"

using namespace posefuse;
using namespace posefuse::sim;

namespace {

using std::numbers::pi;

Eigen::Matrix3Xd rest_joints() {
  Eigen::Matrix3Xd joints(3, body::kNumJoints);
  for (int j = 0; j < body::kNumJoints; ++j) joints.col(j) = Eigen::Vector3d(0.05 * j, 0.9 + 0.03 * j, 0.01 * j);
  return joints;
}

std::vector<double> frame_times(double duration_s, double rate_hz = 30.0) {
  std::vector<double> t;
  for (int i = 0; i <= static_cast<int>(duration_s * rate_hz); ++i) t.push_back(i / rate_hz);
  return t;
}

double largest(const std::vector<Eigen::Matrix3Xd>& wobble, std::size_t begin, std::size_t end) {
  double out = 0.0;
  for (std::size_t i = begin; i < end; ++i) out = std::max(out, wobble[i].colwise().norm().maxCoeff());
  return out;
}

TEST(SoftTissue, NoWobbleAtRestOrAtConstantVelocity) {
  const SoftTissueOptions options;
  const auto still = segment_wobble([](double) { return rest_joints(); }, frame_times(3.0), options);
  EXPECT_EQ(largest(still, 0, still.size()), 0.0);
  const Eigen::Vector3d velocity(1.5, -0.4, 2.0);  // m/s, a brisk walk sideways
  const auto gliding = segment_wobble(
      [&](double t) -> Eigen::Matrix3Xd { return rest_joints().colwise() + t * velocity; }, frame_times(3.0), options);
  // Second differences of a linear motion: rounding only.
  EXPECT_LT(largest(gliding, 0, gliding.size()), 1e-9);
}

TEST(SoftTissue, BoundedAndRingingDownAfterAStop) {
  SoftTissueOptions options;
  // A punch-like shake: 15 cm at 3 Hz (peak acceleration 53 m/s^2) for 2 s, then an abrupt stop.
  const auto shake = [](double t) -> Eigen::Matrix3Xd {
    const double x = t < 2.0 ? 0.15 * std::sin(2 * pi * 3.0 * t) : 0.0;
    return rest_joints().colwise() + Eigen::Vector3d(x, 0.0, 0.0);
  };
  const std::vector<double> times = frame_times(5.0);
  const auto wobble = segment_wobble(shake, times, options);
  const double peak = largest(wobble, 0, 61);
  std::printf("shake: peak %.2f mm (bound %.1f mm); after the stop 0-0.5 s %.2f mm, 1.5-3 s %.4f mm\n", 1e3 * peak,
              1e3 * options.max_displacement_m, 1e3 * largest(wobble, 61, 76), 1e3 * largest(wobble, 106, 151));
  EXPECT_GT(peak, 0.5 * options.max_displacement_m);  // it does wobble
  EXPECT_LT(peak, options.max_displacement_m);
  // Ring-down: amplitude ~ exp(-zeta omega t) = exp(-6.3 / s * t); 1.5 s later below 1e-4 of it.
  EXPECT_GT(largest(wobble, 61, 76), 0.1 * peak);
  EXPECT_LT(largest(wobble, 106, 151), 1e-3 * peak);
  // Deterministic, and off means off.
  EXPECT_EQ(segment_wobble(shake, times, options)[40], wobble[40]);
  options.enabled = false;
  EXPECT_EQ(largest(segment_wobble(shake, times, options), 0, times.size()), 0.0);
}

TEST(SoftTissue, BadInputNamesTheField) {
  SoftTissueOptions options;
  options.damping_ratio = -1;
  const auto field_of = [](const std::function<void()>& f) {
    try {
      f();
    } catch (const Error& e) {
      return std::string(e.field());
    }
    return std::string("no error");
  };
  EXPECT_EQ(field_of([&] { validate(options); }), "soft_tissue.damping_ratio");
  EXPECT_EQ(field_of([] { segment_wobble([](double) { return rest_joints(); }, {0.0, 1.0, 0.5}, {}); }), "times_s");
  EXPECT_EQ(field_of([] { segment_wobble([](double) { return Eigen::Matrix3Xd(3, 3); }, {0.0}, {}); }), "joints_at");
}

TEST(SoftTissue, MeshMovesOnlyWhereFleshIsLooseAndNeverBeyondTheBound) {
  const auto fitted = body::make_template(body::Sex::kMale);
  const RenderModel render =
      make_render_model(*fitted, Eigen::VectorXd::Zero(body::kTemplateNumBetas), ClothingOptions{}, 1);
  const SoftTissueSkin skin(render.model->weights, render.surface_vertices);
  const double max_m = SoftTissueOptions{}.max_displacement_m;
  Eigen::Matrix3Xd segments(3, body::kNumJoints);
  for (int j = 0; j < body::kNumJoints; ++j) segments.col(j) = Eigen::Vector3d(1.0, 0.0, 0.0) * max_m;
  const Eigen::Matrix3Xd rest = render.model->v_template;
  Eigen::Matrix3Xd moved = rest;
  skin.apply(segments, Eigen::Matrix3d::Identity(), moved);
  double upper_arm = 0, hand = 0, largest_move = 0;
  for (int v = 0; v < render.surface_vertices; ++v) {
    const double d = (moved.col(v) - rest.col(v)).norm();
    largest_move = std::max(largest_move, d);
    int dominant = 0;
    render.model->weights.row(v).toDense().maxCoeff(&dominant);
    if (dominant == body::kRightShoulder) upper_arm = std::max(upper_arm, d);
    if (dominant == body::kRightHand || dominant == body::kHead) hand = std::max(hand, d);
  }
  EXPECT_LE(largest_move, max_m + 1e-12);
  EXPECT_GT(upper_arm, 0.95 * max_m);  // loosest (weights blend a little even at the core)
  EXPECT_LT(hand, 0.5 * max_m);        // only blended in at the wrist and neck borders
  for (int v = render.surface_vertices; v < moved.cols(); ++v) EXPECT_EQ(moved.col(v), rest.col(v));  // ghosts
}

class DepthSink : public session::ChunkSink {
 public:
  void write(const session::SessionChunk& chunk) override {
    if (chunk.has_depth()) depth.push_back(session::decode_depth(chunk.depth()));
  }
  void finish() override {}
  std::vector<cv::Mat> depth;
};

TEST(SoftTissue, SessionSurfaceWobblesButImuAndJointTruthDoNot) {
  SimSessionOptions o;
  o.duration_s = 2.0;
  o.motion = "air_punching";
  o.motion_options.exercise.speed = 2.0;
  o.depth_intrinsics = sim::testing::quarter_kinect_intrinsics();
  o.color = false;
  o.depth_noise.axial_sigma_base_m = 0.0;  // geometry only: differences come from the surface
  o.depth_noise.axial_sigma_quadratic_per_m = 0.0;
  o.depth_noise.flying_pixel_probability = 0.0;
  DepthSink with_sink, without_sink;
  const SimTruth with = simulate_session(o, with_sink);
  o.soft_tissue.enabled = false;
  const SimTruth without = simulate_session(o, without_sink);
  ASSERT_EQ(with.devices.size(), without.devices.size());
  for (std::size_t d = 0; d < with.devices.size(); ++d) {
    ASSERT_EQ(with.devices[d].W_from_A.size(), without.devices[d].W_from_A.size());
    for (std::size_t k = 0; k < with.devices[d].W_from_A.size(); ++k) {
      ASSERT_EQ(with.devices[d].W_from_A[k].coeffs(), without.devices[d].W_from_A[k].coeffs());
    }
  }
  ASSERT_EQ(with.frames.size(), without.frames.size());
  int differing_pixels = 0;
  EXPECT_EQ(cv::countNonZero(with_sink.depth[0] != without_sink.depth[0]), 0);  // at rest at t = 0
  for (std::size_t f = 0; f < with.frames.size(); ++f) {
    EXPECT_EQ(with.frames[f].smpl_joints_K, without.frames[f].smpl_joints_K);
    EXPECT_EQ(with.frames[f].imu_p_K, without.frames[f].imu_p_K);
    differing_pixels += cv::countNonZero(with_sink.depth[f] != without_sink.depth[f]);
  }
  std::printf("air punching 2 s: %d depth pixels differ with wobble on\n", differing_pixels);
  EXPECT_GT(differing_pixels, 0);
}

}  // namespace
