#include "raycast/mesh_scene.hpp"

#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <algorithm>
#include <map>
#include <numbers>
#include <random>

#include "common/error.hpp"
#include "raycast/triangle_closest_point.hpp"

namespace posefuse::raycast {
namespace {

struct TestMesh {
  Eigen::Matrix3Xd vertices;
  Eigen::Matrix3Xi faces;
};

// Icosahedron subdivided `levels` times and projected onto the sphere; outward faces.
TestMesh icosphere(const Eigen::Vector3d& centre, double radius, int levels) {
  const double t = (1 + std::sqrt(5.0)) / 2;
  std::vector<Eigen::Vector3d> v = {{-1, t, 0},  {1, t, 0},  {-1, -t, 0}, {1, -t, 0}, {0, -1, t},  {0, 1, t},
                                    {0, -1, -t}, {0, 1, -t}, {t, 0, -1},  {t, 0, 1},  {-t, 0, -1}, {-t, 0, 1}};
  for (auto& p : v) p.normalize();
  std::vector<Eigen::Vector3i> f = {{0, 11, 5},  {0, 5, 1},  {0, 1, 7},  {0, 7, 10}, {0, 10, 11}, {1, 5, 9}, {5, 11, 4},
                                    {11, 10, 2}, {10, 7, 6}, {7, 1, 8},  {3, 9, 4},  {3, 4, 2},   {3, 2, 6}, {3, 6, 8},
                                    {3, 8, 9},   {4, 9, 5},  {2, 4, 11}, {6, 2, 10}, {8, 6, 7},   {9, 8, 1}};
  for (int level = 0; level < levels; ++level) {
    std::map<std::pair<int, int>, int> midpoint;
    auto mid = [&](int a, int b) {
      auto key = std::minmax(a, b);
      auto it = midpoint.find(key);
      if (it != midpoint.end()) return it->second;
      v.push_back((v[a] + v[b]).normalized());
      return midpoint[key] = static_cast<int>(v.size()) - 1;
    };
    std::vector<Eigen::Vector3i> next;
    for (const auto& tri : f) {
      const int ab = mid(tri[0], tri[1]), bc = mid(tri[1], tri[2]), ca = mid(tri[2], tri[0]);
      next.insert(next.end(), {{tri[0], ab, ca}, {tri[1], bc, ab}, {tri[2], ca, bc}, {ab, bc, ca}});
    }
    f = std::move(next);
  }
  TestMesh mesh;
  mesh.vertices.resize(3, static_cast<Eigen::Index>(v.size()));
  for (size_t i = 0; i < v.size(); ++i) mesh.vertices.col(static_cast<Eigen::Index>(i)) = centre + radius * v[i];
  mesh.faces.resize(3, static_cast<Eigen::Index>(f.size()));
  for (size_t i = 0; i < f.size(); ++i) mesh.faces.col(static_cast<Eigen::Index>(i)) = f[i];
  return mesh;
}

// Box with half extents `half`, rotated by `K_from_box` about its centre.
TestMesh box(const Eigen::Vector3d& centre, const Eigen::Vector3d& half, const Eigen::Matrix3d& K_from_box) {
  TestMesh mesh;
  mesh.vertices.resize(3, 8);
  for (int c = 0; c < 8; ++c)
    mesh.vertices.col(c) =
        centre + K_from_box * Eigen::Vector3d((c & 1) ? half.x() : -half.x(), (c & 2) ? half.y() : -half.y(),
                                              (c & 4) ? half.z() : -half.z());
  mesh.faces.resize(3, 12);
  mesh.faces << 0, 0, 4, 4, 0, 0, 2, 2, 0, 0, 1, 1,  //
      2, 3, 5, 7, 1, 5, 6, 7, 4, 6, 3, 7,            //
      3, 1, 7, 6, 5, 4, 7, 3, 6, 2, 7, 5;
  return mesh;
}

TEST(MeshScene, SphereDepthMatchesAnalyticWithinOneMillimetre) {
  const DepthCamera camera{DepthIntrinsics{}};
  const Eigen::Vector3d centre(0.3, -0.2, 2.0);
  const double radius = 0.3;
  const TestMesh sphere = icosphere(centre, radius, 5);
  MeshScene scene(EmbreeDevice::shared(), sphere.faces, static_cast<int>(sphere.vertices.cols()));
  scene.update_vertices(sphere.vertices);
  RenderImages images;
  scene.render(camera, 3, images);
  int compared = 0, hits = 0;
  for (int row = 0; row < camera.height(); ++row)
    for (int col = 0; col < camera.width(); ++col) {
      const size_t pixel = static_cast<size_t>(row) * camera.width() + col;
      const Eigen::Vector3d d = camera.pixel_ray(col, row).cast<double>();  // z = 1
      // |t d - c|^2 = r^2
      const double a = d.squaredNorm(), b = -2 * d.dot(centre), c = centre.squaredNorm() - radius * radius;
      const double disc = b * b - 4 * a * c;
      if (images.depth_mm[pixel] > 0) {
        ++hits;
        EXPECT_EQ(images.body_index[pixel], 3);
        ASSERT_GE(images.face[pixel], 0);
      }
      if (disc <= 0) {
        EXPECT_EQ(images.depth_mm[pixel], 0) << col << "," << row;
        continue;
      }
      const double t = (-b - std::sqrt(disc)) / (2 * a);
      const Eigen::Vector3d normal = (t * d - centre).normalized();
      if (-normal.dot(d.normalized()) < 0.5) continue;  // grazing: the facets differ from the sphere
      ASSERT_GT(images.depth_mm[pixel], 0) << col << "," << row;
      EXPECT_LE(std::abs(images.depth_mm[pixel] - 1000 * t), 1.0) << col << "," << row;
      // Face id and barycentrics reproduce the hit point.
      const Eigen::Vector3i f = sphere.faces.col(images.face[pixel]);
      const double u = images.u[pixel], v = images.v[pixel];
      const Eigen::Vector3d p =
          u * sphere.vertices.col(f[0]) + v * sphere.vertices.col(f[1]) + (1 - u - v) * sphere.vertices.col(f[2]);
      EXPECT_LT((p - images.depth_mm[pixel] / 1000.0 * d).norm(), 0.002);
      ++compared;
    }
  EXPECT_GT(compared, 5000);
  EXPECT_GT(hits, compared);
  // The hit rectangle is the tightest one around every hit.
  int col_begin = camera.width(), col_end = 0, row_begin = camera.height(), row_end = 0;
  for (int row = 0; row < camera.height(); ++row)
    for (int col = 0; col < camera.width(); ++col) {
      if (images.face[static_cast<size_t>(row) * camera.width() + col] < 0) continue;
      col_begin = std::min(col_begin, col);
      col_end = std::max(col_end, col + 1);
      row_begin = std::min(row_begin, row);
      row_end = std::max(row_end, row + 1);
    }
  EXPECT_EQ(images.hit_col_begin, col_begin);
  EXPECT_EQ(images.hit_col_end, col_end);
  EXPECT_EQ(images.hit_row_begin, row_begin);
  EXPECT_EQ(images.hit_row_end, row_end);
}

TEST(MeshScene, RotatedBoxDepthMatchesAnalyticWithinOneMillimetre) {
  const DepthCamera camera{DepthIntrinsics{}};
  const Eigen::Vector3d centre(-0.2, 0.1, 1.5), half(0.25, 0.15, 0.2);
  const Eigen::Matrix3d K_from_box =
      (Eigen::AngleAxisd(0.5, Eigen::Vector3d::UnitY()) * Eigen::AngleAxisd(0.3, Eigen::Vector3d::UnitX()))
          .toRotationMatrix();
  const TestMesh mesh = box(centre, half, K_from_box);
  MeshScene scene(EmbreeDevice::shared(), mesh.faces, 8);
  scene.update_vertices(mesh.vertices);
  RenderImages images;
  scene.render(camera, 0, images);
  int compared = 0;
  for (int row = 0; row < camera.height(); ++row)
    for (int col = 0; col < camera.width(); ++col) {
      const size_t pixel = static_cast<size_t>(row) * camera.width() + col;
      const Eigen::Vector3d d = camera.pixel_ray(col, row).cast<double>();
      // Slab test in the box frame.
      const Eigen::Vector3d o = K_from_box.transpose() * (-centre), dir = K_from_box.transpose() * d;
      double t_in = 0, t_out = 1e9;
      for (int k = 0; k < 3; ++k) {
        double t0 = (-half[k] - o[k]) / dir[k], t1 = (half[k] - o[k]) / dir[k];
        if (t0 > t1) std::swap(t0, t1);
        t_in = std::max(t_in, t0);
        t_out = std::min(t_out, t1);
      }
      const bool hit = t_in < t_out;
      const double margin = t_out - t_in;  // skip rays that only clip an edge
      if (hit && margin > 0.01) {
        ASSERT_GT(images.depth_mm[pixel], 0) << col << "," << row;
        EXPECT_LE(std::abs(images.depth_mm[pixel] - 1000 * t_in), 1.0);
        ++compared;
      } else if (!hit) {
        // Near-miss rays within float precision of an edge may hit; others must not.
        const Eigen::Vector3d closest = o + std::max(0.0, t_in) * dir;
        if ((closest.cwiseAbs() - half).maxCoeff() > 0.005) {
          EXPECT_EQ(images.depth_mm[pixel], 0) << col << "," << row;
        }
      }
    }
  EXPECT_GT(compared, 5000);
}

TEST(MeshScene, RefitFollowsMovedVertices) {
  const DepthCamera camera{DepthIntrinsics{}};
  TestMesh sphere = icosphere({0, 0, 2}, 0.2, 3);
  MeshScene scene(EmbreeDevice::shared(), sphere.faces, static_cast<int>(sphere.vertices.cols()));
  scene.update_vertices(sphere.vertices);
  RenderImages images;
  scene.render(camera, 0, images);
  const size_t centre_pixel = 212 * 512 + 256;
  EXPECT_NEAR(images.depth_mm[centre_pixel], 1800, 1);
  sphere.vertices.colwise() += Eigen::Vector3d(0, 0, 0.5);
  scene.update_vertices(sphere.vertices);
  scene.render(camera, 0, images);
  EXPECT_NEAR(images.depth_mm[centre_pixel], 2300, 1);
  sphere.vertices.colwise() += Eigen::Vector3d(1.0, 0, 0);  // out of the centre pixel's view
  scene.update_vertices(sphere.vertices);
  scene.render(camera, 0, images);
  EXPECT_EQ(images.depth_mm[centre_pixel], 0);
  EXPECT_EQ(images.face[centre_pixel], -1);
}

TEST(MeshScene, VisibilityOfSurfacePoints) {
  const Eigen::Vector3d centre(0, 0, 2);
  const TestMesh sphere = icosphere(centre, 0.3, 3);
  MeshScene scene(EmbreeDevice::shared(), sphere.faces, static_cast<int>(sphere.vertices.cols()));
  scene.update_vertices(sphere.vertices);
  const std::vector<bool> visible = scene.visible(sphere.vertices);
  for (Eigen::Index i = 0; i < sphere.vertices.cols(); ++i) {
    const Eigen::Vector3d p = sphere.vertices.col(i);
    const double facing = -(p - centre).normalized().dot(p.normalized());  // > 0 faces the camera
    // Near the silhouette the facets differ from the true sphere, so leave a band out.
    if (facing > 0.05) {
      EXPECT_TRUE(visible[static_cast<size_t>(i)]) << i;
    } else if (facing < -0.2) {
      EXPECT_FALSE(visible[static_cast<size_t>(i)]) << i;
    }
  }
  const Eigen::Matrix3Xd behind = (Eigen::Matrix3Xd(3, 2) << 0, 0, 0, 0, 3, -1).finished();
  const auto v = scene.visible(behind);
  EXPECT_FALSE(v[0]);  // hidden behind the sphere
  EXPECT_TRUE(v[1]);   // off to the side, nothing in between
}

TEST(MeshScene, FirstHitsAgreeWithTheRenderAndTheSurfaceConvention) {
  const Eigen::Vector3d centre(0.1, -0.05, 2);
  const TestMesh sphere = icosphere(centre, 0.3, 3);
  MeshScene scene(EmbreeDevice::shared(), sphere.faces, static_cast<int>(sphere.vertices.cols()));
  scene.update_vertices(sphere.vertices);
  const DepthCamera camera(DepthIntrinsics{});
  RenderImages images;
  scene.render(camera, 0, images);
  // Rays through points at an arbitrary distance along pixel rays: a hit on the front of the sphere
  // with the render's face and barycentrics, or a miss where the render saw nothing.
  std::vector<Eigen::Vector3d> through;
  std::vector<int> pixel;
  for (int row = 150; row < 280; row += 13)
    for (int col = 180; col < 340; col += 11) {
      through.push_back(0.7 * camera.pixel_ray(col, row).cast<double>());
      pixel.push_back(row * camera.width() + col);
    }
  std::vector<ClosestPoint> hits;
  scene.first_hits(through, hits);
  ASSERT_EQ(hits.size(), through.size());
  int hit_count = 0;
  for (size_t i = 0; i < hits.size(); ++i) {
    const int p = pixel[i];
    ASSERT_EQ(hits[i].face, images.face[static_cast<size_t>(p)]) << i;
    if (hits[i].face < 0) continue;
    ++hit_count;
    EXPECT_NEAR(hits[i].u, images.u[static_cast<size_t>(p)], 1e-5);
    EXPECT_NEAR(hits[i].v, images.v[static_cast<size_t>(p)], 1e-5);
    const Eigen::Vector3i f = sphere.faces.col(hits[i].face);
    const Eigen::Vector3d on_face = hits[i].u * sphere.vertices.col(f[0]) + hits[i].v * sphere.vertices.col(f[1]) +
                                    (1 - hits[i].u - hits[i].v) * sphere.vertices.col(f[2]);
    EXPECT_LT((on_face - hits[i].point).norm(), 1e-5);
    EXPECT_NEAR(hits[i].point.z(), images.depth_mm[static_cast<size_t>(p)] * 1e-3, 6e-4);
    EXPECT_LT((hits[i].point - centre).dot(hits[i].point), 0);  // front side: outward normal faces the camera
  }
  EXPECT_GT(hit_count, 40);
}

TEST(MeshScene, ClosestPointMatchesBruteForce) {
  const TestMesh sphere = icosphere({0.1, 0.2, 2}, 0.3, 2);
  MeshScene scene(EmbreeDevice::shared(), sphere.faces, static_cast<int>(sphere.vertices.cols()));
  scene.update_vertices(sphere.vertices);
  std::mt19937 rng(4);
  std::uniform_real_distribution<double> uni(-0.6, 0.6);
  for (int trial = 0; trial < 200; ++trial) {
    const Eigen::Vector3d p = Eigen::Vector3d(0.1, 0.2, 2) + Eigen::Vector3d(uni(rng), uni(rng), uni(rng));
    double best = 1e9;
    for (Eigen::Index f = 0; f < sphere.faces.cols(); ++f) {
      const Eigen::Vector3d a = sphere.vertices.col(sphere.faces(0, f)), b = sphere.vertices.col(sphere.faces(1, f)),
                            c = sphere.vertices.col(sphere.faces(2, f));
      const Eigen::Vector3d w = closest_point_barycentric(p, a, b, c);
      best = std::min(best, (w[0] * a + w[1] * b + w[2] * c - p).norm());
    }
    const ClosestPoint found = scene.closest_point(p);
    EXPECT_NEAR(found.distance, best, 1e-6);
    const Eigen::Vector3i f = sphere.faces.col(found.face);
    const Eigen::Vector3d rebuilt = found.u * sphere.vertices.col(f[0]) + found.v * sphere.vertices.col(f[1]) +
                                    (1 - found.u - found.v) * sphere.vertices.col(f[2]);
    EXPECT_LT((rebuilt - found.point).norm(), 1e-6);
  }
}

TEST(TriangleClosestPoint, RegionsOfTheTriangle) {
  const Eigen::Vector3d a(0, 0, 0), b(1, 0, 0), c(0, 1, 0);
  EXPECT_TRUE(closest_point_barycentric({0.2, 0.3, 1}, a, b, c).isApprox(Eigen::Vector3d(0.5, 0.2, 0.3)));
  EXPECT_TRUE(closest_point_barycentric({-1, -1, 0}, a, b, c).isApprox(Eigen::Vector3d(1, 0, 0)));
  EXPECT_TRUE(closest_point_barycentric({2, -1, 0}, a, b, c).isApprox(Eigen::Vector3d(0, 1, 0)));
  EXPECT_TRUE(closest_point_barycentric({1, 1, 0}, a, b, c).isApprox(Eigen::Vector3d(0, 0.5, 0.5)));
}

TEST(MeshScene, SharesOneDeviceAndRejectsBadInput) {
  EXPECT_EQ(EmbreeDevice::shared(), EmbreeDevice::shared());
  const TestMesh sphere = icosphere({0, 0, 2}, 0.3, 1);
  EXPECT_THROW(MeshScene(EmbreeDevice::shared(), sphere.faces, 5), Error);
  MeshScene scene(EmbreeDevice::shared(), sphere.faces, static_cast<int>(sphere.vertices.cols()));
  RenderImages images;
  EXPECT_THROW(scene.render(DepthCamera{DepthIntrinsics{}}, 0, images), Error);  // no vertices yet
  EXPECT_THROW(scene.update_vertices(Eigen::Matrix3Xd::Zero(3, 4)), Error);
  Eigen::Matrix3Xd bad = sphere.vertices;
  bad(1, 3) = std::nan("");
  EXPECT_THROW(scene.update_vertices(bad), Error);
}

}  // namespace
}  // namespace posefuse::raycast

#include "body/body_evaluator.hpp"
#include "body/template_generator.hpp"

namespace posefuse::raycast {
namespace {

// The template rendered from the front has no pinholes: no ray slips through a shared edge
// (the mesh has a seam of vertices exactly on the camera's centre column).
TEST(MeshScene, TemplateRenderIsWatertight) {
  for (body::Sex sex : {body::Sex::kMale, body::Sex::kFemale}) {
    const auto model = body::make_template(sex);
    const body::PoseLayout layout = body::PoseLayout::upper_body();
    body::BodyEvaluator eval(model, layout);
    Eigen::VectorXd theta = layout.zero();
    theta[layout.index_of("pelvis_y")] = 180 * (std::numbers::pi / 180);
    theta[layout.index_of("translation_y")] = -0.92;
    theta[layout.index_of("translation_z")] = 2.6;
    eval.evaluate(Eigen::VectorXd::Zero(10), theta, body::Derivatives::kNone);
    MeshScene scene(EmbreeDevice::shared(), model->faces, model->num_vertices());
    scene.update_vertices(eval.vertices());
    DepthIntrinsics intrinsics;
    intrinsics.k1 = intrinsics.k2 = intrinsics.k3 = 0;  // centre column rays lie exactly in x = 0
    intrinsics.width = 400;
    intrinsics.height = 480;
    intrinsics.fx = intrinsics.fy = 560;
    intrinsics.cx = 200;
    intrinsics.cy = 240;
    const DepthCamera camera(intrinsics);
    RenderImages images;
    scene.render(camera, 1, images);
    // The camera is outside a closed, outward-facing mesh, so every first hit is on a face that
    // faces the camera; a ray slipping through a shared edge would hit the back side instead.
    int back_hits = 0, body_pixels = 0;
    for (int row = 0; row < images.height; ++row)
      for (int col = 0; col < images.width; ++col) {
        const int f = images.face[static_cast<size_t>(row) * images.width + col];
        if (f < 0) continue;
        ++body_pixels;
        const Eigen::Vector3d a = eval.vertices().col(model->faces(0, f)), b = eval.vertices().col(model->faces(1, f)),
                              c = eval.vertices().col(model->faces(2, f));
        back_hits += (b - a).cross(c - a).dot(camera.pixel_ray(col, row).cast<double>()) > 0;
      }
    EXPECT_GT(body_pixels, 10000);
    EXPECT_EQ(back_hits, 0);
  }
}

}  // namespace
}  // namespace posefuse::raycast
