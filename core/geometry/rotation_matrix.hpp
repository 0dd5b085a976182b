#pragma once
// Rotation matrix -> quaternion by van Waveren's method (paper 1, ref. [16]; used by II-D for
// the vector observation and by II-F for the panel axes).
#include "geometry/quaternion.hpp"

namespace posefuse::geometry {

using Mat3 = Eigen::Matrix3d;

// The unit quaternion of the rotation matrix R (column-vector convention, v' = R v), so that
// quat_from_rotation_matrix(K_from_A_matrix) is K_from_A. Picks the largest of w, x, y, z as the
// pivot (trace first, then the largest diagonal element) so the division is always by a value
// >= 1/2 and the result keeps full precision near 180 degrees. Returns the member of {q, -q}
// with the pivot component positive. R must be a finite rotation matrix; a finite matrix that is
// only nearly orthonormal gives the normalised quaternion of its nearby rotation.
// Throws posefuse::Error (kInvalidArgument, field "rotation_matrix") on a non-finite entry.
Quat quat_from_rotation_matrix(const Mat3& R);

}  // namespace posefuse::geometry
