#pragma once
// The body model a result directory was fitted with: the template named by calibration.json's
// body_shape.body_model and its personalised betas.
#include <Eigen/Core>
#include <memory>
#include <string>
#include <vector>

#include "body/smpl_model.hpp"
#include "session/result_reader.hpp"

namespace posefuse::gltf {

struct FittedShape {
  std::shared_ptr<const body::SmplModel> model;
  Eigen::VectorXd beta;               // the model's size
  std::vector<std::string> warnings;  // what had to be assumed (no betas, no body model)
};

// Without a calibration report, betas or body model it falls back to the mean shape and the male
// template and says so in `warnings`. Throws posefuse::Error (kInvalidArgument)
// "calibration.json:body_shape.betas" for more betas than the template has.
FittedShape fitted_shape(const session::ResultDirectory& results);

}  // namespace posefuse::gltf
