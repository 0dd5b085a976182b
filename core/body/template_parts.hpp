#pragma once
// Internal to the template generator: which tube each vertex was swept in, so that skinning
// weights only blend joints of the same limb (a thigh must not follow the other leg).
#include <vector>

#include "body/template_generator.hpp"

namespace posefuse::body {

enum class BodyPart { kTorso, kLeftArm, kRightArm, kLeftLeg, kRightLeg, kHead };

struct LabelledTemplateGeometry {
  TemplateGeometry geometry;
  std::vector<BodyPart> parts;  // one per vertex
};

LabelledTemplateGeometry build_template_geometry_with_parts(const BodyDimensions& dimensions);

}  // namespace posefuse::body
