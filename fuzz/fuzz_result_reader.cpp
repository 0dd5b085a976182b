// The result reader (session/result_reader.*) on a result directory made from the input
// (file_tree.hpp: files, links, FIFOs, folders under the layout's names): the reader returns or
// throws posefuse::Error, never hangs on a FIFO, and what it returns holds what its header
// promises: finite unit quaternions, joint indices in range, one value and confidence per angle,
// joint_angles.csv times strictly increasing.
#include <cmath>
#include <cstddef>
#include <cstdint>

#include "../tests/eval/result_fixture.hpp"
#include "common/error.hpp"
#include "file_tree.hpp"
#include "measures/joint_angles.hpp"
#include "seeds.hpp"
#include "session/result_reader.hpp"

using namespace posefuse;

namespace {

void check_unit(const geometry::Quat& q) {
  if (!(std::abs(q.norm() - 1.0) <= 1e-3)) fuzz::invariant_failed("a quaternion read is not a unit one");
}

void check(const session::ResultDirectory& r) {
  for (const auto* by_device : {&r.imu_orientations, &r.forearm_orientations}) {
    for (const auto& [device, rows] : *by_device) {
      for (const session::TimedOrientation& row : rows) check_unit(row.q);
    }
  }
  for (const session::JointRow& row : r.smpl_joints) {
    if (row.joint < 0 || row.joint >= 24) fuzz::invariant_failed("SMPL joint index");
  }
  for (const session::JointRow& row : r.camera_joints) {
    if (row.joint < 0 || row.joint >= 25) fuzz::invariant_failed("camera joint index");
  }
  for (const session::JointRotationRow& row : r.smpl_joint_rotations) check_unit(row.K_from_joint);
  for (const session::ForearmRow& row : r.forearms) check_unit(row.K_from_F);
  for (const session::RecoveredRow& row : r.recovered) check_unit(row.K_from_F);
  for (std::size_t i = 0; i < r.joint_angles.size(); ++i) {
    const session::AngleRow& row = r.joint_angles[i];
    if (row.deg.size() != measures::kAngleCount || row.confidence.size() != measures::kAngleCount) {
      fuzz::invariant_failed("angle columns");
    }
    if (i > 0 && row.t_us <= r.joint_angles[i - 1].t_us) fuzz::invariant_failed("joint angle times");
  }
}

}  // namespace

extern "C" int LLVMFuzzerInitialize(int*, char***) {
  fuzz::init_harness([] {
    fuzz::ScratchTree scratch;
    result_fixture::FixtureSpec spec;
    spec.frames = 2;
    result_fixture::write_fixture(scratch.root() / "results", spec);
    fuzz::Seeds seeds{{"fixture", fuzz::tree_bytes(fuzz::entries_of_directory(scratch.root() / "results"))}};
    // A FIFO and a link where the reader expects files.
    seeds.push_back({"fifo", fuzz::tree_bytes({{'p', "smpl_joints.csv", ""},
                                               {'l', "camera_joints.csv", "/dev/zero"},
                                               {'d', "imu_orientations", ""},
                                               {'l', "imu_orientations/x.csv", "../../outside.csv"}})});
    return seeds;
  });
  return 0;
}

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  static const fuzz::ScratchTree scratch;
  const auto results = scratch.root() / "results";
  scratch.make(results, fuzz::tree_entries(data, size));
  try {
    check(session::read_result_files(results));
  } catch (const Error&) {
  }
  std::filesystem::remove_all(results);
  return 0;
}
