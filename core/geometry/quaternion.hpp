#pragma once
// Quaternion notation shared by every stage (paper 1, II-C).
//
// A rotation is named by what it maps: `K_from_A` takes vectors expressed in frame A to frame K,
// v_K = K_from_A * v_A, and rotations chain as K_from_W * W_from_A == K_from_A.
// We use Eigen's unit quaternions; serialised forms are scalar-first [w x y z].
#include <Eigen/Core>
#include <Eigen/Geometry>

namespace posefuse::geometry {

using Quat = Eigen::Quaterniond;
using Vec3 = Eigen::Vector3d;
using Vec4 = Eigen::Vector4d;

// Scalar-first serialisation [w x y z].
inline Vec4 to_wxyz(const Quat& q) { return {q.w(), q.x(), q.y(), q.z()}; }
inline Quat from_wxyz(const Vec4& wxyz) { return Quat(wxyz[0], wxyz[1], wxyz[2], wxyz[3]); }

// Exponential map: the rotation by |rv| radians about rv/|rv|. Exact for small angles too.
Quat quat_from_rotation_vector(const Vec3& rotation_vector_rad);

// Logarithmic map, inverse of quat_from_rotation_vector; angle in [0, pi].
Vec3 rotation_vector_from_quat(const Quat& q);

// Smallest angle (rad, in [0, pi]) of the rotation that takes a to b; sign-invariant.
double angle_between(const Quat& a, const Quat& b);

// The member of {q, -q} whose dot product with `reference` is non-negative (paper 1, eq. 2).
Quat same_hemisphere(const Quat& q, const Quat& reference);

}  // namespace posefuse::geometry
