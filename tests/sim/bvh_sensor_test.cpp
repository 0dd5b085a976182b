#include "sim/bvh_sensor.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <sstream>

#include "common/error.hpp"
#include "sim/uniform_cubic_spline.hpp"

using posefuse::Error;
using namespace posefuse::sim;

namespace {

Eigen::VectorXd scalar(double x) { return Eigen::VectorXd::Constant(1, x); }

// A root turning about its (BVH) Y axis at `rate_deg_s`, 60 fps, with a child 10 cm away.
BvhClip turning_clip(double rate_deg_s, int frames) {
  std::ostringstream s;
  s.precision(17);
  s << "HIERARCHY\nROOT Root\n{\n OFFSET 0 100 0\n CHANNELS 6 Xposition Yposition Zposition "
       "Zrotation Yrotation Xrotation\n JOINT Child\n {\n  OFFSET 10 0 0\n  CHANNELS 3 Zrotation "
       "Yrotation Xrotation\n  End Site\n  {\n   OFFSET 1 0 0\n  }\n }\n}\nMOTION\nFrames: "
    << frames << "\nFrame Time: " << 1.0 / 60 << "\n";
  for (int f = 0; f < frames; ++f) s << "0 0 0 0 " << rate_deg_s * f / 60.0 << " 0 0 0 0\n";
  return parse_bvh(s.str());
}

}  // namespace

TEST(UniformCubicSpline, InterpolatesSmoothly) {
  std::vector<Eigen::VectorXd> linear, wave;
  const double h = 0.05;
  for (int k = 0; k <= 80; ++k) {
    linear.push_back(scalar(3.0 - 2.0 * k * h));
    wave.push_back(scalar(std::sin(2.0 * k * h)));
  }
  const UniformCubicSpline line(1.0, h, linear);
  const UniformCubicSpline sine(1.0, h, wave);
  for (int k = 0; k <= 80; ++k) EXPECT_NEAR(sine.at(1.0 + k * h)[0], wave[static_cast<std::size_t>(k)][0], 1e-12);
  for (double t = 1.0; t <= 5.0; t += 0.0123) EXPECT_NEAR(line.at(t)[0], 3.0 - 2.0 * (t - 1.0), 1e-12);
  // Away from the natural end conditions a smooth function is reproduced to O(h^4).
  for (double t = 2.0; t <= 4.0; t += 0.0123) EXPECT_NEAR(sine.at(t)[0], std::sin(2.0 * (t - 1.0)), 1e-5);
  EXPECT_DOUBLE_EQ(sine.t_end_s(), 5.0);
  EXPECT_THROW(UniformCubicSpline(0.0, h, {scalar(1.0)}), Error);
  EXPECT_THROW(UniformCubicSpline(0.0, 0.0, linear), Error);
  EXPECT_THROW(UniformCubicSpline(0.0, h, {scalar(1.0), Eigen::VectorXd::Zero(2)}), Error);
  EXPECT_THROW(UniformCubicSpline(0.0, h, {scalar(1.0), scalar(std::nan(""))}), Error);
}

// Beyond its ends the spline continues along the end tangents: value and slope continue, the
// curvature (zero at a natural end) too. Gaussian smoothing keeps a straight line straight up to
// the ends (point reflection) and smooths a step symmetrically.
TEST(UniformCubicSpline, ContinuesAlongTheEndTangents) {
  std::vector<Eigen::VectorXd> wave;
  const double h = 0.05;
  for (int k = 0; k <= 40; ++k) wave.push_back(scalar(std::sin(1.3 * k * h) + 0.5 * k * h));
  const UniformCubicSpline spline(0.0, h, wave);
  const double e = 1e-6;
  for (double end : {spline.t_begin_s(), spline.t_end_s()}) {
    const double slope_in =
        end == 0.0 ? (spline.at(e)[0] - spline.at(0.0)[0]) / e : (spline.at(end)[0] - spline.at(end - e)[0]) / e;
    const double outside = end == 0.0 ? -0.01 : end + 0.01;
    EXPECT_NEAR(spline.at_extended(outside)[0], spline.at(end)[0] + (outside - end) * slope_in, 1e-6);
    EXPECT_EQ(spline.at_extended(end)[0], spline.at(end)[0]);
  }
  EXPECT_EQ(spline.at_extended(1.0)[0], spline.at(1.0)[0]);

  std::vector<Eigen::VectorXd> line, step;
  for (int k = 0; k < 20; ++k) {
    line.push_back(scalar(2.0 - 0.3 * k));
    step.push_back(scalar(k < 10 ? 0.0 : 1.0));
  }
  const auto smooth_line = gaussian_smooth(line, 2.5);
  for (int k = 0; k < 20; ++k) EXPECT_NEAR(smooth_line[static_cast<std::size_t>(k)][0], 2.0 - 0.3 * k, 1e-12) << k;
  const auto smooth_step = gaussian_smooth(step, 1.5);
  for (int k = 0; k < 10; ++k) {
    EXPECT_NEAR(smooth_step[static_cast<std::size_t>(k)][0] + smooth_step[static_cast<std::size_t>(19 - k)][0], 1.0,
                1e-12);
  }
  EXPECT_EQ(gaussian_smooth(step, 0.0)[3][0], 0.0);
}

// A sensor on a joint turning at 2 rad/s about the vertical: away from the clip's ends the
// synthesized kinematics read that rate about the joint's y axis and the centripetal
// acceleration of its 10 cm offset.
TEST(BvhSensor, TurningJointGivesRateAndCentripetalAcceleration) {
  const double rate = 2.0;
  const BvhClip clip = turning_clip(rate * 180.0 / 3.14159265358979323846, 121);
  BvhSensorMount mount;
  mount.joint = "Root";
  mount.offset_joint_m = Vec3(0.1, 0, 0);
  const SensorKinematics motion(bvh_sensor_trajectory(clip, mount, 0.01));
  EXPECT_NEAR(motion.t_end_s(), 2.0 - 0.002, 1e-9);
  for (double t = 0.3; t <= 1.7; t += 0.01) {
    const SensorMotion m = motion.at(t);
    EXPECT_LT((m.omega_A_rad_s - Vec3(0, rate, 0)).norm(), 1e-3) << t;
    EXPECT_NEAR(m.a_W_m_s2.norm(), rate * rate * 0.1, 1e-3) << t;
    EXPECT_NEAR(m.p_W_m.z(), 1.0, 1e-12);  // 100 cm up in BVH's Y is 1 m up in W
  }
  // Smoothing leaves a constant turn alone (away from the ends, where the kernel is cut).
  const SensorKinematics smoothed(bvh_sensor_trajectory(clip, mount, 0.01, 0.02));
  for (double t = 0.3; t <= 1.7; t += 0.01) {
    EXPECT_LT((smoothed.at(t).omega_A_rad_s - Vec3(0, rate, 0)).norm(), 1e-3) << t;
  }
  EXPECT_THROW(bvh_sensor_trajectory(clip, mount, 0.01, -1.0), Error);
  mount.joint = "Nope";
  EXPECT_THROW(bvh_sensor_trajectory(clip, mount, 0.01), Error);
}
