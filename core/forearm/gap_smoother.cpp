#include "forearm/gap_smoother.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <optional>
#include <string>
#include <tuple>

#include <Eigen/Sparse>

#include "common/error.hpp"
#include "forearm/paper_recovery.hpp"

namespace posefuse::forearm {

namespace {

using Triplets = std::vector<Eigen::Triplet<double>>;

// The elbow anchor's error over the window, a polynomial in tau with this many terms: a line, as
// the boundary windows (strap and anchor both seen) determine it. Tried a cubic (value and slope
// at both ends, for the SDK's bias turning with a period of seconds): worse, since a cubic also
// fits the smooth inertial drift inside the gap that the anchor is there to correct (synthetic
// 4 s gap, sigma 0.03 m: 46 against 40 mm RMS). Also tried: the attitude leak e(t) linear between
// knots 0.5 s apart with a random-walk prior (0.1 m/s^2 per knot) instead of e0 + tau e1: better
// on the synthetic arm (4 s gap 28 against 85 mm RMS without the anchor), worse on the body render
// (4.4 s gaps 290 / 78 / 131 / 116 mm without the anchor, 57 / 42 / 53 / 46 with it, against
// 47 / 40 / 39 / 45 mm here): the knots let the leak wander where nothing inside the gap pins it.
constexpr int kAnchorTerms = 2;

// Rows of J and r for one linearisation point; columns 3i..3i+2 are p_i, then b_A, e0_K, e1_K,
// and each elbow anchor's error c0_K, c1_K (the first anchor's, then the second's).
struct LinearSystem {
  Triplets jacobian;
  std::vector<double> residual;
  int add_row() {
    residual.push_back(0.0);
    return static_cast<int>(residual.size()) - 1;
  }
};

struct Problem {
  const GapRecoveryInput* input = nullptr;
  const ArmTimeline* arm = nullptr;
  std::vector<std::size_t> arm_index;  // node i is arm sample arm_index[i]
  std::vector<double> t_s;             // node times, s
  std::vector<Vec3> sphere_centre;     // eq. 13 at each node
  struct Fix {
    std::size_t node;
    double u;
    Vec3 z;
    double sigma_scale = 1.0;
  };
  std::vector<Fix> fixes;  // visible track samples
  // An elbow anchor's samples (Fix::z the anchor position) and its sigmas.
  struct Anchor {
    std::vector<Fix> samples;
    double sigma_m;
    double bias_prior_sigma_m;
  };
  std::array<Anchor, 2> anchors;
  GapSmootherOptions options;

  int bias_column() const { return 3 * static_cast<int>(t_s.size()); }
  int drift0_column() const { return bias_column() + 3; }
  int drift1_column() const { return bias_column() + 6; }
  // Anchor a's error c(tau) = sum_k c_k tau^k, k < kAnchorTerms.
  int anchor_column(std::size_t a, int k) const {
    return bias_column() + 9 + 3 * (static_cast<int>(a) * kAnchorTerms + k);
  }
  int columns() const { return anchor_column(anchors.size(), 0); }
  // Time in the window scaled to [-1, 1] for the linear-in-time attitude-leak and anchor terms.
  double tau_at(double t) const {
    const double mid = 0.5 * (t_s.front() + t_s.back()), half = 0.5 * (t_s.back() - t_s.front());
    return (t - mid) / half;
  }
  double tau(std::size_t i) const { return tau_at(t_s[i]); }
  double tau(const Fix& f) const { return tau_at((1.0 - f.u) * t_s[f.node] + f.u * t_s[f.node + 1]); }

  LinearSystem linearise(const Eigen::VectorXd& x) const {
    LinearSystem sys;
    const std::size_t n = t_s.size();
    const double sa = options.acc_sigma_m_s2;
    const Vec3 b = x.segment<3>(bias_column());
    const Vec3 e0 = x.segment<3>(drift0_column());
    const Vec3 e1 = x.segment<3>(drift1_column());
    const Vec3& g_K = arm->gravity_K();
    for (std::size_t i = 1; i + 1 < n; ++i) {
      // Second difference on an uneven grid against eq. 12's net acceleration.
      const double h0 = t_s[i] - t_s[i - 1], h1 = t_s[i + 1] - t_s[i];
      const double c_prev = 2.0 / (h0 * (h0 + h1)), c_next = 2.0 / (h1 * (h0 + h1));
      const double c_mid = -(c_prev + c_next);
      const ArmSample& s = input->arm[arm_index[i]];
      const Eigen::Matrix3d R = s.K_from_A.toRotationMatrix();
      const Vec3 second_difference = c_prev * x.segment<3>(3 * static_cast<int>(i - 1)) +
                                     c_mid * x.segment<3>(3 * static_cast<int>(i)) +
                                     c_next * x.segment<3>(3 * static_cast<int>(i + 1));
      const Vec3 r = (second_difference - (R * (s.specific_force_A - b) - g_K - e0 - tau(i) * e1)) / sa;
      for (int k = 0; k < 3; ++k) {
        const int row = sys.add_row();
        sys.residual[static_cast<std::size_t>(row)] = r[k];
        sys.jacobian.emplace_back(row, 3 * static_cast<int>(i - 1) + k, c_prev / sa);
        sys.jacobian.emplace_back(row, 3 * static_cast<int>(i) + k, c_mid / sa);
        sys.jacobian.emplace_back(row, 3 * static_cast<int>(i + 1) + k, c_next / sa);
        for (int c = 0; c < 3; ++c) sys.jacobian.emplace_back(row, bias_column() + c, R(k, c) / sa);
        sys.jacobian.emplace_back(row, drift0_column() + k, 1.0 / sa);
        sys.jacobian.emplace_back(row, drift1_column() + k, tau(i) / sa);
      }
    }
    const double sp = options.position_sigma_m;
    for (const Fix& f : fixes) {
      const int a = 3 * static_cast<int>(f.node);
      const Vec3 p = (1.0 - f.u) * x.segment<3>(a) + f.u * x.segment<3>(a + 3);
      for (int k = 0; k < 3; ++k) {
        const int row = sys.add_row();
        sys.residual[static_cast<std::size_t>(row)] = (p[k] - f.z[k]) / sp;
        sys.jacobian.emplace_back(row, a + k, (1.0 - f.u) / sp);
        if (f.u > 0.0) sys.jacobian.emplace_back(row, a + 3 + k, f.u / sp);
      }
    }
    // The elbow anchors, robust: a residual of norm |r| > k (in sigmas) is weighted by k / |r|, so
    // it costs k |r| instead of |r|^2 (iteratively reweighted at each linearisation).
    const double k = options.anchor_huber_k;
    for (std::size_t a = 0; a < anchors.size(); ++a) {
      for (const Fix& f : anchors[a].samples) {
        const double sc = anchors[a].sigma_m * f.sigma_scale;
        const int node = 3 * static_cast<int>(f.node);
        double power[kAnchorTerms];
        power[0] = 1.0;
        for (int j = 1; j < kAnchorTerms; ++j) power[j] = power[j - 1] * tau(f);
        Vec3 anchor_error = Vec3::Zero();
        for (int j = 0; j < kAnchorTerms; ++j) anchor_error += power[j] * x.segment<3>(anchor_column(a, j));
        const Vec3 p = (1.0 - f.u) * x.segment<3>(node) + f.u * x.segment<3>(node + 3);
        const Vec3 r = (p + anchor_error - f.z) / sc;
        const double w = std::sqrt(r.norm() > k ? k / r.norm() : 1.0) / sc;
        for (int c = 0; c < 3; ++c) {
          const int row = sys.add_row();
          sys.residual[static_cast<std::size_t>(row)] = w * sc * r[c];
          sys.jacobian.emplace_back(row, node + c, w * (1.0 - f.u));
          if (f.u > 0.0) sys.jacobian.emplace_back(row, node + 3 + c, w * f.u);
          for (int j = 0; j < kAnchorTerms; ++j) sys.jacobian.emplace_back(row, anchor_column(a, j) + c, w * power[j]);
        }
      }
    }
    if (options.use_shoulder_sphere) {
      const double ss = options.sphere_sigma_m;
      for (std::size_t i = 0; i < n; ++i) {
        const Vec3 d = x.segment<3>(3 * static_cast<int>(i)) - sphere_centre[i];
        const double norm = d.norm();
        if (norm < 1e-9) continue;
        const int row = sys.add_row();
        sys.residual[static_cast<std::size_t>(row)] = (norm - input->model.d_ul_m) / ss;
        for (int k = 0; k < 3; ++k) {
          sys.jacobian.emplace_back(row, 3 * static_cast<int>(i) + k, d[k] / norm / ss);
        }
      }
    }
    const double sb = options.bias_prior_sigma_m_s2, se = options.leak_prior_sigma_m_s2;
    for (int c = 0; c < 3; ++c) {
      for (const auto& [column, value, sigma] :
           {std::tuple{bias_column(), b[c], sb}, std::tuple{drift0_column(), e0[c], se},
            std::tuple{drift1_column(), e1[c], se}}) {
        const int row = sys.add_row();
        sys.residual[static_cast<std::size_t>(row)] = value / sigma;
        sys.jacobian.emplace_back(row, column + c, 1.0 / sigma);
      }
      for (std::size_t a = 0; a < anchors.size(); ++a) {
        const double s_anchor = anchors[a].bias_prior_sigma_m;
        for (int j = 0; j < kAnchorTerms; ++j) {
          const int row = sys.add_row();
          sys.residual[static_cast<std::size_t>(row)] = x[anchor_column(a, j) + c] / s_anchor;
          sys.jacobian.emplace_back(row, anchor_column(a, j) + c, 1.0 / s_anchor);
        }
      }
    }
    return sys;
  }
};

double cost_of(const LinearSystem& sys) {
  double c = 0.0;
  for (double r : sys.residual) c += r * r;
  return c;
}

void check_options(const GapSmootherOptions& o) {
  if (!(o.boundary_window_s > 0.0)) throw_invalid("options.boundary_window_s", "must be > 0");
  if (!(o.acc_sigma_m_s2 > 0.0) || !(o.position_sigma_m > 0.0) || !(o.sphere_sigma_m > 0.0) ||
      !(o.bias_prior_sigma_m_s2 > 0.0) || !(o.leak_prior_sigma_m_s2 > 0.0) || !(o.anchor_sigma_m > 0.0) ||
      !(o.anchor_bias_prior_sigma_m > 0.0) || !(o.second_anchor_sigma_m > 0.0) ||
      !(o.second_anchor_bias_prior_sigma_m > 0.0)) {
    throw_invalid("options", "every sigma must be > 0");
  }
  if (!(o.anchor_huber_k > 0.0)) throw_invalid("options.anchor_huber_k", "must be > 0");
}

}  // namespace

RecoveredGap recover_gap_smoother(const GapRecoveryInput& input, const GapSpan& gap,
                                  const GapSmootherOptions& options) {
  check_options(options);
  // The paper's recovery validates everything, checks the boundaries, and is the start point.
  const RecoveredGap start = recover_gap_paper(input, gap, {.boundary_window_s = options.boundary_window_s});
  const ArmTimeline arm(input);
  const BoundaryState entry = fit_boundary_line(input.track, gap.t_start_us, -1, options.boundary_window_s);
  const BoundaryState exit = fit_boundary_line(input.track, gap.t_end_us, +1, options.boundary_window_s);

  const auto window_us = static_cast<std::int64_t>(std::llround(options.boundary_window_s * 1e6));
  Problem problem;
  problem.input = &input;
  problem.arm = &arm;
  problem.options = options;
  for (std::size_t i = 0; i < input.arm.size(); ++i) {
    const std::int64_t t = input.arm[i].t_us;
    if (t < gap.t_start_us - window_us || t > gap.t_end_us + window_us) continue;
    problem.arm_index.push_back(i);
    problem.t_s.push_back(static_cast<double>(t) * 1e-6);
  }
  const std::size_t n = problem.t_s.size();  // >= 2: the arm covers [t_start, t_end]
  Eigen::VectorXd x = Eigen::VectorXd::Zero(problem.columns());
  for (std::size_t i = 0; i < n; ++i) {
    const std::int64_t t = input.arm[problem.arm_index[i]].t_us;
    const double ts = static_cast<double>(t) * 1e-6;
    Vec3 p;
    if (t < gap.t_start_us) {
      p = entry.p_K + entry.v_K * (ts - static_cast<double>(gap.t_start_us) * 1e-6);
    } else if (t > gap.t_end_us) {
      p = exit.p_K + exit.v_K * (ts - static_cast<double>(gap.t_end_us) * 1e-6);
    } else {
      p = position_at(start, t);
    }
    x.segment<3>(3 * static_cast<int>(i)) = p;
    problem.sphere_centre.push_back(arm.sphere_centre_K(static_cast<double>(t)));
  }
  const double t_first = problem.t_s.front(), t_last = problem.t_s.back();
  const auto fix_at = [&](std::int64_t t_us, const Vec3& z) -> std::optional<Problem::Fix> {
    const double ts = static_cast<double>(t_us) * 1e-6;
    if (ts < t_first || ts > t_last) return std::nullopt;
    const auto it = std::upper_bound(problem.t_s.begin(), problem.t_s.end(), ts);
    const std::size_t k = std::min(static_cast<std::size_t>(it - problem.t_s.begin()) - 1, n - 2);
    return Problem::Fix{k, (ts - problem.t_s[k]) / (problem.t_s[k + 1] - problem.t_s[k]), z};
  };
  for (const TrackSample& s : input.track) {
    if (!s.visible) continue;
    if (const auto fix = fix_at(s.t_us, s.p_K)) problem.fixes.push_back(*fix);
  }
  problem.anchors[0] = {{}, options.anchor_sigma_m, options.anchor_bias_prior_sigma_m};
  problem.anchors[1] = {{}, options.second_anchor_sigma_m, options.second_anchor_bias_prior_sigma_m};
  if (options.use_elbow_anchor) {
    for (const auto& [samples, anchor] : {std::pair{&input.elbow_anchor, &problem.anchors[0]},
                                          std::pair{&input.second_elbow_anchor, &problem.anchors[1]}}) {
      for (const ElbowAnchorSample& a : *samples) {
        if (auto fix = fix_at(a.t_us, a.p_K)) {
          fix->sigma_scale = a.sigma_scale;
          anchor->samples.push_back(*fix);
        }
      }
    }
  }

  // Gauss-Newton with step halving; the normal equations are banded (plus the bias columns).
  const int columns = problem.columns();
  LinearSystem sys = problem.linearise(x);
  double cost = cost_of(sys);
  for (int iteration = 0; iteration < options.max_iterations; ++iteration) {
    Eigen::SparseMatrix<double> J(static_cast<int>(sys.residual.size()), columns);
    J.setFromTriplets(sys.jacobian.begin(), sys.jacobian.end());
    const Eigen::Map<const Eigen::VectorXd> r(sys.residual.data(), static_cast<int>(sys.residual.size()));
    const Eigen::SparseMatrix<double> H = J.transpose() * J;
    Eigen::SimplicialLDLT<Eigen::SparseMatrix<double>> solver(H);
    if (solver.info() != Eigen::Success) {
      throw Error(ErrorCode::kInternal, "smoother", "normal equations are singular");
    }
    const Eigen::VectorXd step = solver.solve(-(J.transpose() * r));
    double scale = 1.0;
    bool improved = false;
    for (int halving = 0; halving < 8; ++halving, scale *= 0.5) {
      const Eigen::VectorXd trial = x + scale * step;
      LinearSystem trial_sys = problem.linearise(trial);
      const double trial_cost = cost_of(trial_sys);
      if (trial_cost <= cost) {
        improved = cost - trial_cost > 1e-10 * cost;
        x = trial;
        sys = std::move(trial_sys);
        cost = trial_cost;
        break;
      }
    }
    if (!improved) break;
  }

  RecoveredGap out;
  out.span = gap;
  out.t_us = start.t_us;
  for (std::int64_t t : out.t_us) {
    const double ts = static_cast<double>(t) * 1e-6;
    const auto it = std::upper_bound(problem.t_s.begin(), problem.t_s.end(), ts);
    const std::size_t k =
        std::min(static_cast<std::size_t>(std::max<std::ptrdiff_t>(it - problem.t_s.begin(), 1)) - 1, n - 2);
    const double u = std::clamp((ts - problem.t_s[k]) / (problem.t_s[k + 1] - problem.t_s[k]), 0.0, 1.0);
    out.p_K.push_back((1.0 - u) * x.segment<3>(3 * static_cast<int>(k)) +
                      u * x.segment<3>(3 * static_cast<int>(k + 1)));
  }
  return out;
}

}  // namespace posefuse::forearm
