#include "body/mesh_export.hpp"

#include <fstream>
#include <iomanip>

#include "common/error.hpp"

namespace posefuse::body {
namespace {

void check_mesh(const Eigen::Matrix3Xd& vertices, const Eigen::Matrix3Xi& faces) {
  if (!vertices.allFinite()) throw_invalid("vertices", "not finite");
  if (faces.size() > 0 && (faces.minCoeff() < 0 || faces.maxCoeff() >= vertices.cols()))
    throw_invalid("faces", "vertex index outside [0, " + std::to_string(vertices.cols()) + ")");
}

std::ofstream open_for_writing(const std::string& path) {
  std::ofstream out(path);
  if (!out) throw Error(ErrorCode::kNotFound, path, "cannot open for writing");
  out << std::fixed << std::setprecision(6);
  return out;
}

bool ends_with(const std::string& s, const std::string& suffix) {
  return s.size() >= suffix.size() && s.compare(s.size() - suffix.size(), suffix.size(), suffix) == 0;
}

}  // namespace

void write_obj(std::ostream& out, const Eigen::Matrix3Xd& vertices, const Eigen::Matrix3Xi& faces) {
  check_mesh(vertices, faces);
  out << "# posefuse body mesh: " << vertices.cols() << " vertices, " << faces.cols() << " faces\n";
  for (Eigen::Index i = 0; i < vertices.cols(); ++i)
    out << "v " << vertices(0, i) << ' ' << vertices(1, i) << ' ' << vertices(2, i) << '\n';
  for (Eigen::Index f = 0; f < faces.cols(); ++f)  // OBJ indices start at 1
    out << "f " << faces(0, f) + 1 << ' ' << faces(1, f) + 1 << ' ' << faces(2, f) + 1 << '\n';
}

void write_ply(std::ostream& out, const Eigen::Matrix3Xd& vertices, const Eigen::Matrix3Xi& faces) {
  check_mesh(vertices, faces);
  out << "ply\nformat ascii 1.0\ncomment posefuse body mesh\nelement vertex " << vertices.cols()
      << "\nproperty float x\nproperty float y\nproperty float z\nelement face " << faces.cols()
      << "\nproperty list uchar int vertex_indices\nend_header\n";
  for (Eigen::Index i = 0; i < vertices.cols(); ++i)
    out << vertices(0, i) << ' ' << vertices(1, i) << ' ' << vertices(2, i) << '\n';
  for (Eigen::Index f = 0; f < faces.cols(); ++f)
    out << "3 " << faces(0, f) << ' ' << faces(1, f) << ' ' << faces(2, f) << '\n';
}

void write_skeleton(std::ostream& out, const Eigen::Matrix3Xd& joints, const std::array<int, kNumJoints>& parents) {
  if (joints.cols() != kNumJoints) throw_invalid("joints", std::to_string(joints.cols()) + " joints, expected 24");
  if (!joints.allFinite()) throw_invalid("joints", "not finite");
  out << "# posefuse skeleton v1: index name parent x y z (metres)\n";
  for (int j = 0; j < kNumJoints; ++j)
    out << j << ' ' << smpl_joint_names()[j] << ' ' << parents[j] << ' ' << joints(0, j) << ' ' << joints(1, j) << ' '
        << joints(2, j) << '\n';
}

void write_mesh_file(const std::string& path, const Eigen::Matrix3Xd& vertices, const Eigen::Matrix3Xi& faces) {
  const bool obj = ends_with(path, ".obj"), ply = ends_with(path, ".ply");
  if (!obj && !ply) throw_invalid(path, "mesh file must end in .obj or .ply");
  std::ofstream out = open_for_writing(path);
  if (obj) write_obj(out, vertices, faces);
  else write_ply(out, vertices, faces);
  if (!out) throw Error(ErrorCode::kDataLoss, path, "write failed");
}

void write_skeleton_file(const std::string& path, const Eigen::Matrix3Xd& joints,
                         const std::array<int, kNumJoints>& parents) {
  std::ofstream out = open_for_writing(path);
  write_skeleton(out, joints, parents);
  if (!out) throw Error(ErrorCode::kDataLoss, path, "write failed");
}

}  // namespace posefuse::body
