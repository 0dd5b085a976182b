// posefuse-sim: generates a synthetic recording with ground truth (docs/simulator.md).
#include <unistd.h>
#include <chrono>
#include <cstdio>
#include <iostream>
#include <string>

#include "common/error.hpp"
#include "session/file_bytes.hpp"
#include "tools/sim/calibration_capture_files.hpp"
#include "tools/sim/sim_options_file.hpp"
#include "tools/sim/sim_run.hpp"

namespace {

const char* const kUsage =
    "usage: posefuse-sim (--out DIR | --chunk-file FILE) [--options FILE] [--seed N] [--duration S|clip]\n"
    "                    [--gt DIR] [--contact-sheet PNG] [--threads N] [--bvh-joint-map FILE|mocap21|cmu31] "
    "[--quiet]\n"
    "       posefuse-sim --list-options\n"
    "       posefuse-sim calibrate DIR   (frame calibration, paper 1 II-F, of a calibration_capture/ folder)\n"
    "Writes a simulated session (recording directory with gt/ inside, or a chunk file with\n"
    "FILE.gt/ beside it). Flags override the options file. See docs/simulator.md.\n";

int fail(const std::string& message) {
  std::cerr << "posefuse-sim: " << message << '\n';
  return 1;
}

}  // namespace

int main(int argc, char** argv) {
  using namespace posefuse;
  try {
    if (argc >= 2 && std::string(argv[1]) == "calibrate") {
      if (argc != 3) return fail(std::string("calibrate takes one folder\n") + kUsage);
      const std::string report = tools::calibration_report(tools::calibrate_capture_directory(argv[2]));
      std::cout << report;
      session::write_file_bytes(std::filesystem::path(argv[2]) / "calibration_result.txt", report);
      std::cerr << "posefuse-sim: written " << (std::filesystem::path(argv[2]) / "calibration_result.txt").string()
                << "; pass the last line as the session header option (header.json \"options\")\n";
      return 0;
    }
    tools::SimRunRequest request;
    std::optional<std::string> options_file, seed, duration, threads, joint_map;
    bool quiet = false;
    for (int i = 1; i < argc; ++i) {
      const std::string flag = argv[i];
      const auto value = [&]() -> std::string {
        if (i + 1 >= argc) throw Error(ErrorCode::kInvalidArgument, flag, "needs a value");
        return argv[++i];
      };
      if (flag == "--out") request.out_directory = value();
      else if (flag == "--chunk-file") request.chunk_file = value();
      else if (flag == "--gt") request.gt_directory = value();
      else if (flag == "--contact-sheet") request.contact_sheet = value();
      else if (flag == "--options") options_file = value();
      else if (flag == "--seed") seed = value();
      else if (flag == "--duration") duration = value();
      else if (flag == "--threads") threads = value();
      else if (flag == "--bvh-joint-map") joint_map = value();
      else if (flag == "--quiet") quiet = true;
      else if (flag == "--list-options") {
        for (const auto& key : tools::sim_option_keys()) std::cout << key.key << "\t" << key.meaning << '\n';
        return 0;
      } else if (flag == "--help" || flag == "-h") {
        std::cout << kUsage;
        return 0;
      } else {
        return fail("unknown flag '" + flag + "'\n" + kUsage);
      }
    }
    if (options_file) tools::apply_sim_options_file(*options_file, request.options);
    if (seed) tools::apply_sim_option("seed", *seed, "--seed", request.options);
    if (duration) tools::apply_sim_option("duration_s", *duration, "--duration", request.options);
    if (threads) tools::apply_sim_option("threads", *threads, "--threads", request.options);
    if (joint_map) tools::apply_sim_option("bvh_joint_map", *joint_map, "--bvh-joint-map", request.options);

    const auto start = std::chrono::steady_clock::now();
    const bool tty = isatty(STDERR_FILENO) != 0;
    std::int64_t last_decile = -1;
    const auto progress = [&](const sim::SimProgress& p) {
      if (quiet) return;
      const double elapsed = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
      const double fraction = static_cast<double>(p.frames_done) / static_cast<double>(p.frames_total);
      const std::int64_t decile = static_cast<std::int64_t>(fraction * 10);
      if (!tty && decile == last_decile && p.frames_done < p.frames_total) return;  // logs: every 10 %
      last_decile = decile;
      const double eta = fraction > 0 ? elapsed * (1 - fraction) / fraction : 0;
      std::fprintf(stderr, "%sposefuse-sim: frame %lld/%lld (%.0f %%), %.1f s elapsed, ETA %.1f s%s", tty ? "\r" : "",
                   static_cast<long long>(p.frames_done), static_cast<long long>(p.frames_total), 100 * fraction,
                   elapsed, eta, tty ? "" : "\n");
    };
    const tools::SimRunResult result = tools::run_simulation(request, progress);
    for (const std::string& warning : result.warnings) std::cerr << "posefuse-sim: warning: " << warning << '\n';
    if (!quiet) {
      const double elapsed = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
      std::fprintf(stderr, "%sposefuse-sim: %.3f s session, %lld frames, %llu chunks in %.1f s; ground truth in %s\n",
                   tty ? "\n" : "", result.duration_s, static_cast<long long>(result.frames),
                   static_cast<unsigned long long>(result.chunks), elapsed, result.gt_directory.string().c_str());
    }
    return 0;
  } catch (const posefuse::Error& e) {
    return fail(e.what());  // "<field>: <message>"
  } catch (const std::exception& e) {
    return fail(e.what());
  }
}
