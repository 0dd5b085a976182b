#include "gltf/fitted_shape.hpp"

#include "body/template_generator.hpp"
#include "common/error.hpp"

namespace posefuse::gltf {

FittedShape fitted_shape(const session::ResultDirectory& results) {
  FittedShape out;
  const v1::BodyShape* shape = results.calibration ? &results.calibration->body_shape() : nullptr;
  body::Sex sex = body::Sex::kMale;
  if (shape && shape->body_model() == v1::BodyShape::TEMPLATE_FEMALE) {
    sex = body::Sex::kFemale;
  } else if (!shape || shape->body_model() != v1::BodyShape::TEMPLATE_MALE) {
    out.warnings.push_back(
        "calibration.json names no body model (body_shape.body_model): the male template is assumed");
  }
  out.model = body::make_template(sex);
  out.beta = Eigen::VectorXd::Zero(out.model->num_betas());
  if (!shape || shape->betas_size() == 0) {
    out.warnings.push_back("calibration.json has no body_shape.betas: the mesh has the template's mean shape");
    return out;
  }
  if (shape->betas_size() > out.model->num_betas())
    throw_invalid(
        "calibration.json:body_shape.betas",
        std::to_string(shape->betas_size()) + " betas, the template has " + std::to_string(out.model->num_betas()));
  for (int b = 0; b < shape->betas_size(); ++b) out.beta[b] = shape->betas(b);
  return out;
}

}  // namespace posefuse::gltf
