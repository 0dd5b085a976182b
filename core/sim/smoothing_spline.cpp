#include "sim/smoothing_spline.hpp"

#include <algorithm>
#include <cmath>

#include <Eigen/SparseCholesky>
#include <Eigen/SparseCore>

#include "common/error.hpp"
#include "sim/option_checks.hpp"

namespace posefuse::sim {
namespace {

using Sparse = Eigen::SparseMatrix<double>;

// Q (n x (n-2)) and R ((n-2) x (n-2)) of the header.
void reinsch_matrices(Eigen::Index n, double h, Sparse& Q, Sparse& R) {
  std::vector<Eigen::Triplet<double>> q, r;
  for (Eigen::Index i = 0; i + 2 < n; ++i) {
    q.emplace_back(i, i, 1.0 / h);
    q.emplace_back(i + 1, i, -2.0 / h);
    q.emplace_back(i + 2, i, 1.0 / h);
    r.emplace_back(i, i, 2.0 * h / 3.0);
    if (i + 3 < n) {
      r.emplace_back(i, i + 1, h / 6.0);
      r.emplace_back(i + 1, i, h / 6.0);
    }
  }
  Q.resize(n, n - 2);
  R.resize(n - 2, n - 2);
  Q.setFromTriplets(q.begin(), q.end());
  R.setFromTriplets(r.begin(), r.end());
}

Eigen::VectorXd solve(const Eigen::VectorXd& y, const Sparse& Q, const Sparse& R, const Sparse& QtQ, double lambda) {
  const Sparse A = R + lambda * QtQ;
  Eigen::SimplicialLDLT<Sparse> ldlt(A);
  if (ldlt.info() != Eigen::Success) throw Error(ErrorCode::kInternal, "smoothing_spline", "factorisation failed");
  const Eigen::VectorXd gamma = ldlt.solve(Q.transpose() * y);
  return y - lambda * (Q * gamma);
}

void check(const Eigen::VectorXd& y, double h_s) {
  require_positive(h_s, "h_s");
  if (!y.allFinite()) throw_invalid("y", "has non-finite values");
}

}  // namespace

double noise_sigma_from_differences(const Eigen::VectorXd& y) {
  if (y.size() < 5) return 0.0;
  std::vector<double> d4(static_cast<std::size_t>(y.size() - 4));
  for (Eigen::Index k = 2; k + 2 < y.size(); ++k) {
    d4[static_cast<std::size_t>(k - 2)] = std::abs(y[k - 2] - 4 * y[k - 1] + 6 * y[k] - 4 * y[k + 1] + y[k + 2]);
  }
  const auto middle = d4.begin() + static_cast<std::ptrdiff_t>(d4.size() / 2);
  std::nth_element(d4.begin(), middle, d4.end());
  return 1.4826 * *middle / std::sqrt(70.0);
}

Eigen::VectorXd smoothing_spline_values(const Eigen::VectorXd& y, double h_s, double lambda) {
  check(y, h_s);
  require_non_negative(lambda, "lambda");
  if (y.size() < 3 || lambda == 0) return y;
  Sparse Q, R;
  reinsch_matrices(y.size(), h_s, Q, R);
  const Sparse QtQ = Q.transpose() * Q;
  return solve(y, Q, R, QtQ, lambda);
}

NoiseChosenSmoothing smooth_by_noise_level(const Eigen::VectorXd& y, double h_s) {
  check(y, h_s);
  NoiseChosenSmoothing out;
  out.values = y;
  out.noise_sigma = noise_sigma_from_differences(y);
  if (y.size() < 3 || out.noise_sigma == 0) return out;
  Sparse Q, R;
  reinsch_matrices(y.size(), h_s, Q, R);
  const Sparse QtQ = Q.transpose() * Q;
  const double target = static_cast<double>(y.size()) * out.noise_sigma * out.noise_sigma;
  // lambda / h^3 is dimensionless: from far below noise level to a straight line.
  double low = std::log(1e-8 * std::pow(h_s, 3)), high = std::log(1e12 * std::pow(h_s, 3));
  Eigen::VectorXd f = solve(y, Q, R, QtQ, std::exp(high));
  if ((y - f).squaredNorm() <= target) {
    out.values = f;
    out.lambda = std::exp(high);
    return out;
  }
  for (int i = 0; i < 50 && high - low > 1e-3; ++i) {
    const double mid = 0.5 * (low + high);
    f = solve(y, Q, R, QtQ, std::exp(mid));
    ((y - f).squaredNorm() > target ? high : low) = mid;
  }
  out.lambda = std::exp(low);
  out.values = solve(y, Q, R, QtQ, out.lambda);
  return out;
}

std::vector<Eigen::VectorXd> smooth_by_noise_level(const std::vector<Eigen::VectorXd>& frames, double h_s) {
  if (frames.empty()) return frames;
  const Eigen::Index channels = frames.front().size();
  std::vector<Eigen::VectorXd> out(frames.size(), Eigen::VectorXd(channels));
  Eigen::VectorXd y(static_cast<Eigen::Index>(frames.size()));
  for (Eigen::Index c = 0; c < channels; ++c) {
    for (std::size_t k = 0; k < frames.size(); ++k) {
      if (frames[k].size() != channels) throw_invalid("frames[" + std::to_string(k) + "]", "has another size");
      y[static_cast<Eigen::Index>(k)] = frames[k][c];
    }
    const Eigen::VectorXd f = smooth_by_noise_level(y, h_s).values;
    for (std::size_t k = 0; k < frames.size(); ++k) out[k][c] = f[static_cast<Eigen::Index>(k)];
  }
  return out;
}

}  // namespace posefuse::sim
