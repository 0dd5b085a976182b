// Writes a small result directory for the browser test (run_browser_test.sh): the result
// fixture's streams (tests/eval/result_fixture.hpp) and a warnings.txt whose second line holds
// markup that the report must show as text.
#include <cstdio>
#include <fstream>

#include "../eval/result_fixture.hpp"

int main(int argc, char** argv) {
  if (argc != 2) {
    std::fprintf(stderr, "usage: write_report_fixture DIR\n");
    return 2;
  }
  const std::filesystem::path dir = argv[1];
  std::filesystem::remove_all(dir);
  posefuse::result_fixture::FixtureSpec spec;
  spec.level_camera = true;
  spec.frames = 90;
  posefuse::result_fixture::write_fixture(dir, spec);
  std::ofstream(dir / "warnings.txt")
      << "warning [MEASURES_VERTICAL_ASSUMED] joint_angles.thorax: no world orientation\n"
      << "warning [TEST] field: <script>alert(1)</script> & <b>not bold</b>\n";
  return 0;
}
