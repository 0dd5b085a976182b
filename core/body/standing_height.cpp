#include "body/standing_height.hpp"

#include <string>

#include "common/error.hpp"

namespace posefuse::body {

StandingHeight standing_height(const SmplModel& model, const Eigen::VectorXd& beta) {
  if (beta.size() > model.num_betas())
    throw_invalid("beta", "has " + std::to_string(beta.size()) + " entries, the model " +
                              std::to_string(model.num_betas()) + " shape directions");
  Eigen::VectorXd b = Eigen::VectorXd::Zero(model.num_betas());
  b.head(beta.size()) = beta;
  int top = 0, bottom = 0;
  double top_y = 0, bottom_y = 0;
  for (int v = 0; v < model.num_vertices(); ++v) {
    const double y = model.v_template(1, v) + model.shapedirs.row(3 * v + 1).dot(b);
    if (v == 0 || y > top_y) top = v, top_y = y;
    if (v == 0 || y < bottom_y) bottom = v, bottom_y = y;
  }
  StandingHeight out;
  out.height_m = top_y - bottom_y;
  out.gradient = model.shapedirs.row(3 * top + 1) - model.shapedirs.row(3 * bottom + 1);
  return out;
}

}  // namespace posefuse::body
