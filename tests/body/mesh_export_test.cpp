#include "body/mesh_export.hpp"

#include <gtest/gtest.h>

#include <sstream>

#include "body/template_generator.hpp"
#include "common/error.hpp"

namespace posefuse::body {
namespace {

TEST(MeshExport, ObjAndPlyListEveryVertexAndFace) {
  const auto model = make_template(Sex::kMale);
  std::stringstream obj, ply;
  write_obj(obj, model->v_template, model->faces);
  write_ply(ply, model->v_template, model->faces);
  int v = 0, f = 0;
  std::string line;
  Eigen::Vector3d first_vertex;
  Eigen::Vector3i last_face;
  while (std::getline(obj, line)) {
    std::istringstream fields(line);
    std::string tag;
    fields >> tag;
    if (tag == "v" && v++ == 0) fields >> first_vertex.x() >> first_vertex.y() >> first_vertex.z();
    if (tag == "f") {
      ++f;
      fields >> last_face[0] >> last_face[1] >> last_face[2];
    }
  }
  EXPECT_EQ(v, model->num_vertices());
  EXPECT_EQ(f, model->num_faces());
  EXPECT_LT((first_vertex - model->v_template.col(0)).norm(), 1e-5);
  EXPECT_EQ(last_face, (model->faces.col(model->num_faces() - 1).array() + 1).matrix());
  const std::string ply_text = ply.str();
  EXPECT_NE(ply_text.find("element vertex " + std::to_string(model->num_vertices())), std::string::npos);
  EXPECT_NE(ply_text.find("element face " + std::to_string(model->num_faces())), std::string::npos);
}

TEST(MeshExport, SkeletonHasOneLinePerJoint) {
  Eigen::Matrix3Xd joints = Eigen::Matrix3Xd::Random(3, kNumJoints);
  std::stringstream out;
  write_skeleton(out, joints, kSmplParents);
  std::string line;
  std::getline(out, line);
  EXPECT_EQ(line.rfind("# posefuse skeleton v1", 0), 0u);
  for (int j = 0; j < kNumJoints; ++j) {
    ASSERT_TRUE(std::getline(out, line));
    std::istringstream fields(line);
    int index, parent;
    std::string name;
    Eigen::Vector3d p;
    fields >> index >> name >> parent >> p.x() >> p.y() >> p.z();
    EXPECT_EQ(index, j);
    EXPECT_EQ(name, smpl_joint_names()[j]);
    EXPECT_EQ(parent, kSmplParents[j]);
    EXPECT_LT((p - joints.col(j)).norm(), 1e-5);
  }
  EXPECT_THROW(write_skeleton(out, Eigen::Matrix3Xd::Zero(3, 5), kSmplParents), Error);
  EXPECT_THROW(write_mesh_file("/tmp/posefuse_mesh.stl", joints, Eigen::Matrix3Xi::Zero(3, 1)), Error);
  EXPECT_THROW(write_mesh_file("/nonexistent/dir/mesh.obj", joints, Eigen::Matrix3Xi::Zero(3, 1)), Error);
}

}  // namespace
}  // namespace posefuse::body
