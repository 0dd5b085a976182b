#include "session/session_inputs.hpp"

namespace posefuse::session {

const Skeleton* CameraFrame::skeleton(std::uint32_t body_id) const {
  for (const Skeleton& s : skeletons) {
    if (s.body_id == body_id) return &s;
  }
  return nullptr;
}

geometry::PinholeCamera pinhole_camera(const v1::CameraIntrinsics& c) {
  return {static_cast<int>(c.width()),
          static_cast<int>(c.height()),
          c.fx(),
          c.fy(),
          c.cx(),
          c.cy(),
          c.k1(),
          c.k2(),
          c.k3(),
          c.p1(),
          c.p2()};
}

v1::CameraIntrinsics camera_intrinsics(const geometry::PinholeCamera& camera) {
  v1::CameraIntrinsics out;
  out.set_width(static_cast<std::uint32_t>(camera.width));
  out.set_height(static_cast<std::uint32_t>(camera.height));
  out.set_fx(camera.fx);
  out.set_fy(camera.fy);
  out.set_cx(camera.cx);
  out.set_cy(camera.cy);
  out.set_k1(camera.k1);
  out.set_k2(camera.k2);
  out.set_k3(camera.k3);
  out.set_p1(camera.p1);
  out.set_p2(camera.p2);
  return out;
}

SessionCameras session_cameras(const v1::SessionHeader& header) {
  SessionCameras cameras;
  cameras.depth = pinhole_camera(header.depth_intrinsics());
  if (header.has_color_intrinsics()) {
    cameras.color = pinhole_camera(header.color_intrinsics());
    if (header.has_color_from_depth()) {
      const auto& r = header.color_from_depth().rotation();
      const auto& t = header.color_from_depth().translation_m();
      cameras.color_from_depth = geometry::Quat(r.w(), r.x(), r.y(), r.z()).normalized();
      cameras.color_from_depth_m = geometry::Vec3(t.x(), t.y(), t.z());
    }
  }
  cameras.color_rate_hz = header.color_rate_hz();
  return cameras;
}

}  // namespace posefuse::session
