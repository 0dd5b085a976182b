// Writes the glTF validator test's result directory (posed_results.hpp): a few fitted frames.
//   write_gltf_fixture OUT_DIR
#include <cstdio>
#include <exception>

#include "posed_results.hpp"

int main(int argc, char** argv) {
  if (argc != 2) {
    std::fprintf(stderr, "usage: write_gltf_fixture OUT_DIR\n");
    return 2;
  }
  try {
    std::vector<posefuse::gltf_fixture::Pose> poses;
    for (int f = 0; f < 6; ++f) poses.push_back(posefuse::gltf_fixture::fixture_pose(f));
    posefuse::gltf_fixture::write_posed_results(argv[1], poses);
  } catch (const std::exception& e) {
    std::fprintf(stderr, "write_gltf_fixture: %s\n", e.what());
    return 1;
  }
  return 0;
}
