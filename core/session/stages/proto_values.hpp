#pragma once
// Eigen values -> the result schema's Vec3 / Quaternion (wxyz), for the stages.
#include <Eigen/Core>
#include <Eigen/Geometry>

#include "posefuse/v1/types.pb.h"

namespace posefuse::session {

inline v1::Vec3 to_proto(const Eigen::Vector3d& v) {
  v1::Vec3 out;
  out.set_x(v.x());
  out.set_y(v.y());
  out.set_z(v.z());
  return out;
}

inline v1::Quaternion to_proto(const Eigen::Quaterniond& q) {
  v1::Quaternion out;
  out.set_w(q.w());
  out.set_x(q.x());
  out.set_y(q.y());
  out.set_z(q.z());
  return out;
}

}  // namespace posefuse::session
