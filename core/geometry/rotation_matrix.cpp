#include "geometry/rotation_matrix.hpp"

#include <cmath>

#include "common/error.hpp"

namespace posefuse::geometry {

// van Waveren, "From quaternion to matrix and back" (2005): with t = 1 + (signed) sum of the
// diagonal, the pivot component is sqrt(t)/2 and every other component is a sum or difference of
// two off-diagonal elements times s = 1/(2 sqrt(t)). His listing is for row-vector matrices; the
// signs below are for our column-vector convention.
Quat quat_from_rotation_matrix(const Mat3& R) {
  if (!R.allFinite()) throw_invalid("rotation_matrix", "has a non-finite entry");
  const double trace = R(0, 0) + R(1, 1) + R(2, 2);
  double w, x, y, z;
  if (trace > 0.0) {
    const double t = trace + 1.0;
    const double s = 0.5 / std::sqrt(t);
    w = s * t;
    x = (R(2, 1) - R(1, 2)) * s;
    y = (R(0, 2) - R(2, 0)) * s;
    z = (R(1, 0) - R(0, 1)) * s;
  } else if (R(0, 0) > R(1, 1) && R(0, 0) > R(2, 2)) {
    const double t = R(0, 0) - R(1, 1) - R(2, 2) + 1.0;
    const double s = 0.5 / std::sqrt(t);
    x = s * t;
    y = (R(0, 1) + R(1, 0)) * s;
    z = (R(0, 2) + R(2, 0)) * s;
    w = (R(2, 1) - R(1, 2)) * s;
  } else if (R(1, 1) > R(2, 2)) {
    const double t = -R(0, 0) + R(1, 1) - R(2, 2) + 1.0;
    const double s = 0.5 / std::sqrt(t);
    y = s * t;
    x = (R(0, 1) + R(1, 0)) * s;
    z = (R(1, 2) + R(2, 1)) * s;
    w = (R(0, 2) - R(2, 0)) * s;
  } else {
    const double t = -R(0, 0) - R(1, 1) + R(2, 2) + 1.0;
    const double s = 0.5 / std::sqrt(t);
    z = s * t;
    x = (R(0, 2) + R(2, 0)) * s;
    y = (R(1, 2) + R(2, 1)) * s;
    w = (R(1, 0) - R(0, 1)) * s;
  }
  // Unit already for an orthonormal R; normalising covers nearly orthonormal input. One
  // reciprocal square root and multiplications: this runs once per orientation-filter sample.
  const double inverse_norm = 1.0 / std::sqrt(w * w + x * x + y * y + z * z);
  return Quat(w * inverse_norm, x * inverse_norm, y * inverse_norm, z * inverse_norm);
}

}  // namespace posefuse::geometry
