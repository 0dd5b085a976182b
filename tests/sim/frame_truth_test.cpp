#include "sim/frame_truth.hpp"

#include <gtest/gtest.h>

#include <numbers>

#include "body/template_generator.hpp"
#include "common/error.hpp"
#include "sim/camera_session.hpp"
#include "sim/exercises.hpp"
#include "test_camera.hpp"

using posefuse::Error;
using namespace posefuse::sim;
namespace body = posefuse::body;
namespace raycast = posefuse::raycast;

namespace {

using std::numbers::pi;

// The camera of CameraSessionOptions: 1 m up, 2.5 m in front of the subject, facing it.
Eigen::Isometry3d camera_in_front() {
  return Eigen::Translation3d(0, -1.0, 2.5) * Eigen::AngleAxisd(pi, Eigen::Vector3d::UnitY());
}

class PosedBody {
 public:
  PosedBody()
      : model_(body::make_template(body::Sex::kMale)),
        evaluator_(model_, body::PoseLayout::all_joints()),
        scene_(raycast::EmbreeDevice::shared(), model_->faces, model_->num_vertices()) {}

  FrameTruth truth_at(const BodyMotion& motion, double t, const std::vector<ForearmStrap>& straps,
                      const Eigen::Isometry3d& K_from_R = camera_in_front()) {
    evaluator_.evaluate(Eigen::VectorXd::Zero(10), motion.poses(t), body::Derivatives::kNone);
    scene_.update_vertices(K_from_R * evaluator_.vertices());
    return frame_truth(evaluator_, scene_, K_from_R, straps);
  }
  const body::BodyEvaluator& evaluator() const { return evaluator_; }

 private:
  std::shared_ptr<body::SmplModel> model_;
  body::BodyEvaluator evaluator_;
  raycast::MeshScene scene_;
};

double middle_of(const BodyMotion& m, const std::string& name) {
  for (const MotionPhase& p : m.phases) {
    if (p.name == name) return 0.5 * (p.begin_s + p.end_s);
  }
  throw std::runtime_error("no phase " + name);
}

}  // namespace

TEST(FrameTruth, ForearmFrameStrapAndImuInTheCamera) {
  PosedBody body_model;
  const BodyMotion m = make_exercise("forearm_protocol");
  ForearmStrap strap;
  strap.F_from_A = Quat(Eigen::AngleAxisd(0.2, Vec3::UnitZ()));
  const FrameTruth truth = body_model.truth_at(m, middle_of(m, "calibration_hold"), {strap});
  ASSERT_EQ(truth.forearms.size(), 1u);
  const ForearmTruth& f = truth.forearms[0];
  const Eigen::Isometry3d K_from_R = camera_in_front();
  EXPECT_LT((truth.smpl_joints_K - K_from_R * body_model.evaluator().joints()).cwiseAbs().maxCoeff(), 1e-12);
  ASSERT_EQ(truth.camera_joints_K.cols(), 25);
  EXPECT_LT((f.elbow_K_m - truth.smpl_joints_K.col(body::kRightElbow)).norm(), 1e-12);
  EXPECT_LT((f.wrist_K_m - truth.smpl_joints_K.col(body::kRightWrist)).norm(), 1e-12);
  const Vec3 y = f.K_from_F * Vec3::UnitY();
  EXPECT_LT((y - (f.wrist_K_m - f.elbow_K_m).normalized()).norm(), 1e-9);  // y: elbow -> wrist
  EXPECT_LT((f.strap_K_m - (f.elbow_K_m + strap.strap_to_elbow_m * y)).norm(), 1e-12);
  EXPECT_LT((f.imu_K_m - (f.strap_K_m + strap.strap_radius_m * (f.K_from_F * Vec3::UnitX()))).norm(), 1e-12);
  EXPECT_LT(posefuse::geometry::angle_between(f.K_from_A, f.K_from_F * strap.F_from_A), 1e-12);
  // Calibration pose, seen from the front: the palm faces the camera, i.e. the back of the hand
  // (x_F) points away from it (+z_K); the forearm is up (+y_K) and fully visible.
  EXPECT_GT((f.K_from_F * Vec3::UnitX()).z(), 0.99);
  EXPECT_GT(y.y(), 0.99);
  EXPECT_EQ(f.visible_fraction, 1.0);
  EXPECT_TRUE(f.strap_visible);
  EXPECT_FALSE(f.occluded);
}

// Paper 1's protocol seen from the front: the forearm is hidden behind the head and behind the
// back, visible in the calibration pose and in front of the belly.
TEST(FrameTruth, OcclusionFollowsTheProtocol) {
  PosedBody body_model;
  const BodyMotion m = make_exercise("forearm_protocol");
  const std::vector<ForearmStrap> straps = {ForearmStrap{BodySide::kRight}, ForearmStrap{BodySide::kLeft}};
  for (const char* phase : {"calibration_hold", "behind_head", "in_front_of_belly", "behind_back"}) {
    const FrameTruth truth = body_model.truth_at(m, middle_of(m, phase), straps);
    const ForearmTruth& right = truth.forearms[0];
    const ForearmTruth& left = truth.forearms[1];
    std::printf("%-18s right visible %.2f strap %d | left (hanging) visible %.2f strap %d\n", phase,
                right.visible_fraction, right.strap_visible ? 1 : 0, left.visible_fraction, left.strap_visible ? 1 : 0);
    const bool hidden = std::string(phase) == "behind_head" || std::string(phase) == "behind_back";
    EXPECT_EQ(right.occluded, hidden) << phase;
    EXPECT_EQ(right.strap_visible, !hidden) << phase;
    EXPECT_EQ(left.side, BodySide::kLeft);
    EXPECT_FALSE(left.occluded) << phase;  // the idle left arm hangs in view
  }
  // From behind, the forearm behind the back is in view and the one in front of the belly not.
  const Eigen::Isometry3d behind = Eigen::Translation3d(0, -1.0, 2.5) * Eigen::Isometry3d::Identity();
  EXPECT_FALSE(body_model.truth_at(m, middle_of(m, "behind_back"), straps, behind).forearms[0].occluded);
  EXPECT_TRUE(body_model.truth_at(m, middle_of(m, "in_front_of_belly"), straps, behind).forearms[0].occluded);
}

TEST(FrameTruth, CameraSessionCarriesTheTruth) {
  CameraSessionOptions options;
  options.intrinsics = posefuse::sim::testing::quarter_kinect_intrinsics();
  options.duration_s = 0.2;
  options.forearm_straps = {ForearmStrap{}};
  const BodyMotion m = make_exercise("calibration_pose");
  const CameraSessionResult result = simulate_camera_session(options, body::PoseLayout::all_joints(), m.poses);
  ASSERT_EQ(result.truth.size(), result.t_us.size());
  for (std::size_t f = 0; f < result.truth.size(); ++f) {
    ASSERT_EQ(result.truth[f].forearms.size(), 1u);
    EXPECT_EQ(result.truth[f].camera_joints_K, result.true_camera_joints_K[f]);
  }
  options.forearm_straps[0].strap_to_elbow_m = -1;
  EXPECT_THROW(simulate_camera_session(options, body::PoseLayout::all_joints(), m.poses), Error);
}
