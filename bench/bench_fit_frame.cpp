// Per-frame body-model fit (paper 2, II-F; issue 7): frames rendered from known poses of the
// built-in template are fitted back from perturbed starts by FrameFitter. Prints per-frame fit
// time (median, 95th percentile; wall and thread CPU; one thread), LM iterations and the joint
// error against the rendered truth. The depth preprocessing (prepare_observation) is timed
// separately: it is not part of the LM loop.
//
//   bench_fit_frame [frames=20] [perturb_deg=5] [perturb_m=0.03] [max_iterations=20] [repeats=1]
// repeats > 1 fits every frame that many times (all timed): for profiling the fit alone.
#include <algorithm>
#include <cstdio>
#include <cstdlib>
#include <numbers>
#include <random>
#include <vector>

#include "bench_clock.hpp"
#include "body/template_generator.hpp"
#include "fit/frame_fitter.hpp"
#include "model_frames.hpp"

using namespace posefuse;

namespace {

double percentile(std::vector<double> v, double q) {
  std::sort(v.begin(), v.end());
  return v[static_cast<size_t>(q * static_cast<double>(v.size() - 1) + 0.5)];
}

}  // namespace

int main(int argc, char** argv) {
  const int frames = argc > 1 ? std::atoi(argv[1]) : 20;
  const double perturb_rad = (argc > 2 ? std::atof(argv[2]) : 5.0) * std::numbers::pi / 180;
  const double perturb_m = argc > 3 ? std::atof(argv[3]) : 0.03;
  fit::FitOptions options;
  if (argc > 4) options.max_iterations = std::atoi(argv[4]);
  const int repeats = argc > 5 ? std::max(1, std::atoi(argv[5])) : 1;

  const auto model = body::make_template(body::Sex::kMale);
  const body::PoseLayout layout = body::PoseLayout::upper_body();
  const raycast::DepthCamera camera{raycast::DepthIntrinsics{}};
  const Eigen::VectorXd beta = Eigen::VectorXd::Constant(10, 0.2);
  fit::FrameFitter fitter(model, layout, camera.intrinsics(), options);
  body::BodyEvaluator eval(model, layout);
  std::mt19937 rng(42);
  std::uniform_real_distribution<double> uni(-1, 1);

  double total_fit_cpu_ms = 0;
  long total_iterations = 0;  // over all repeats: CPU per LM iteration = total_fit_cpu_ms / total_iterations
  std::vector<double> fit_wall, fit_cpu, prep_cpu, iterations, start_error, mean_error, max_error, limb_error;
  std::printf(
      "frame  start_mm  mean_mm  max_mm  iters  rejected  E_start    E_end      E_truth    status       cpu_ms\n");
  for (int f = 0; f < frames; ++f) {
    Eigen::VectorXd truth = fit::testing::facing_pose(layout, 2.0 + 0.1 * (f % 5), f);
    for (int d = 6; d < layout.size(); ++d) truth[d] += 0.1 * uni(rng);  // a different pose per frame
    const auto rendered = fit::testing::render_model_frame(model, layout, beta, truth, camera);
    const fit::ForearmDirections imu{fit::testing::forearm_direction(rendered.joints_K, true),
                                     fit::testing::forearm_direction(rendered.joints_K, false)};
    const double prep_start = bench::thread_cpu_seconds();
    const fit::FrameObservation observation =
        fit::prepare_observation(rendered.frame, camera, rendered.skeleton_K, options, imu);
    prep_cpu.push_back(1e3 * (bench::thread_cpu_seconds() - prep_start));
    Eigen::VectorXd start = truth;
    for (int d = 0; d < layout.size(); ++d)
      start[d] += (layout.dof(d).kind == body::DofKind::kTranslation ? perturb_m : perturb_rad) * uni(rng);
    eval.evaluate(beta, start, body::Derivatives::kNone);
    double start_max = 0;
    for (int j : fit::kBgJoints)
      start_max = std::max(start_max, (eval.joints().col(j) - rendered.joints_K.col(j)).norm());

    const fit::EnergyTerms truth_terms = fitter.energy(observation, truth, beta);
    const double truth_energy = truth_terms.total();
    if (std::getenv("FIT_TERMS"))
      std::printf("truth terms: data %.3g bg %.3g bgJoint %.3g float %.3g limit %.3g imu %.3g\n", truth_terms.data,
                  truth_terms.bg, truth_terms.bg_joint, truth_terms.float_term, truth_terms.limit, truth_terms.imu);
    fit::FitResult result;
    for (int r = 0; r < repeats; ++r) {
      const auto wall_start = bench::WallClock::now();
      const double cpu_start = bench::thread_cpu_seconds();
      result = fitter.fit(observation, start, beta);
      fit_cpu.push_back(1e3 * (bench::thread_cpu_seconds() - cpu_start));
      fit_wall.push_back(bench::wall_ms_since(wall_start));
      total_fit_cpu_ms += fit_cpu.back();
      total_iterations += result.iterations;
    }

    if (std::getenv("FIT_TERMS"))
      std::printf("fit terms:   data %.3g bg %.3g bgJoint %.3g float %.3g limit %.3g imu %.3g\n", result.energy.data,
                  result.energy.bg, result.energy.bg_joint, result.energy.float_term, result.energy.limit,
                  result.energy.imu);
    eval.evaluate(beta, result.theta, body::Derivatives::kNone);
    double sum = 0, worst = 0;
    for (int j : fit::kBgJoints) {
      const double e = (eval.joints().col(j) - rendered.joints_K.col(j)).norm();
      sum += e;
      worst = std::max(worst, e);
    }
    if (std::getenv("FIT_JOINTS")) {
      for (int j : fit::kBgJoints)
        std::printf("  %s %.1f", body::smpl_joint_names()[j],
                    1e3 * (eval.joints().col(j) - rendered.joints_K.col(j)).norm());
      std::printf("\n");
    }
    double limb_sum = 0;  // paper 2's Fig. 4 joints
    for (int j : {body::kLeftShoulder, body::kRightShoulder, body::kLeftElbow, body::kRightElbow, body::kLeftWrist,
                  body::kRightWrist})
      limb_sum += (eval.joints().col(j) - rendered.joints_K.col(j)).norm();
    limb_error.push_back(limb_sum / 6);
    iterations.push_back(result.iterations);
    start_error.push_back(start_max);
    mean_error.push_back(sum / fit::kBgJointCount);
    max_error.push_back(worst);
    std::printf("%5d  %8.1f  %7.2f  %6.2f  %5d  %8d  %-9.4g  %-9.4g  %-9.4g  %-12s %6.2f\n", f, 1e3 * start_max,
                1e3 * mean_error.back(), 1e3 * worst, result.iterations, result.rejected_steps,
                result.initial_energy.total(), result.energy.total(), truth_energy, fit::fit_status_name(result.status),
                fit_cpu.back());
  }
  std::printf(
      "\n%d frames, 512x424, N_s = %d, %d DOF, max %d LM iterations, start perturbation %.1f deg / %.3f m per DOF\n",
      frames, options.num_samples, layout.size(), options.max_iterations, perturb_rad * 180 / std::numbers::pi,
      perturb_m);
  std::printf("fit time, thread CPU:   median %.2f ms, p95 %.2f ms\n", percentile(fit_cpu, 0.5),
              percentile(fit_cpu, 0.95));
  std::printf("fit CPU per LM iteration: %.3f ms (%.1f ms over %ld iterations)\n",
              total_fit_cpu_ms / static_cast<double>(std::max(1L, total_iterations)), total_fit_cpu_ms,
              total_iterations);
  std::printf("fit time, wall:         median %.2f ms, p95 %.2f ms\n", percentile(fit_wall, 0.5),
              percentile(fit_wall, 0.95));
  std::printf("preprocessing, CPU:     median %.2f ms (prepare_observation, not in the fit time)\n",
              percentile(prep_cpu, 0.5));
  std::printf("LM iterations:          median %.0f, max %.0f\n", percentile(iterations, 0.5),
              percentile(iterations, 1.0));
  std::printf("start joint error:      median of max %.1f mm\n", 1e3 * percentile(start_error, 0.5));
  std::printf("joint error (16 joints): median of mean %.2f mm, median of max %.2f mm, worst max %.2f mm\n",
              1e3 * percentile(mean_error, 0.5), 1e3 * percentile(max_error, 0.5), 1e3 * percentile(max_error, 1.0));
  std::printf("upper-limb error (shoulders, elbows, wrists): median of mean %.2f mm, worst mean %.2f mm\n",
              1e3 * percentile(limb_error, 0.5), 1e3 * percentile(limb_error, 1.0));
  return 0;
}
