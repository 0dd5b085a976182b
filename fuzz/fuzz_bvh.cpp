// The BVH reader (sim/bvh.*) on arbitrary text: a parsed clip is consistent (parents before
// children, one value per declared channel, frame time > 0), and forward kinematics and
// resampling of it give unit rotations for every joint of every frame.
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <string_view>

#include "../tests/sim/test_rigs.hpp"
#include "common/error.hpp"
#include "seeds.hpp"
#include "sim/bvh.hpp"

using namespace posefuse;

namespace {

void check_unit(const sim::Quat& q, const char* what) {
  if (!(std::abs(q.norm() - 1.0) < 1e-6)) fuzz::invariant_failed(std::string(what) + " is not a unit quaternion");
}

void check_clip(const sim::BvhClip& clip) {
  const sim::BvhSkeleton& skeleton = clip.skeleton;
  int channels = 0;
  for (std::size_t j = 0; j < skeleton.joints.size(); ++j) {
    const sim::BvhJoint& joint = skeleton.joints[j];
    if (joint.parent >= static_cast<int>(j) || (j > 0 && joint.parent < 0)) fuzz::invariant_failed("parent order");
    if (joint.first_channel != channels) fuzz::invariant_failed("first channel");
    channels += static_cast<int>(joint.channels.size());
  }
  if (channels != skeleton.channel_count) fuzz::invariant_failed("channel count");
  if (!(clip.frame_time_s > 0)) fuzz::invariant_failed("frame time");
  for (const sim::BvhLocalPose& pose : clip.frames) {
    const sim::BvhWorldPose world = sim::forward_kinematics(skeleton, pose, 0.01);
    for (const sim::Quat& q : world.W_from_joint) check_unit(q, "a joint's world rotation");
  }
}

}  // namespace

extern "C" int LLVMFuzzerInitialize(int*, char***) {
  fuzz::init_harness([] {
    auto wave = [](int frame, int joint, int channel) { return 5.0 * std::sin(0.3 * frame + joint + channel); };
    return fuzz::Seeds{{"rig21.bvh", sim::testing::rig_text(sim::testing::rig21(), 4, 1.0 / 120, wave)},
                       {"cmu31.bvh", sim::testing::rig_text(sim::testing::rig_cmu31(), 2, 1.0 / 30, wave)}};
  });
  return 0;
}

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  try {
    const sim::BvhClip clip = sim::parse_bvh(std::string_view(reinterpret_cast<const char*>(data), size), "fuzz.bvh");
    check_clip(clip);
    // Twice the clip's own rate: as many frames again, each between two read ones.
    check_clip(sim::resample(clip, 2.0 / clip.frame_time_s));
  } catch (const Error&) {
  }
  return 0;
}
