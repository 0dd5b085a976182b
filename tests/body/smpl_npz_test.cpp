#include "body/smpl_npz.hpp"

#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <limits>

#include "body/body_evaluator.hpp"
#include "common/error.hpp"
#include "npz_writer.hpp"
#include "random_model.hpp"

namespace posefuse::body {
namespace {

using Members = std::vector<std::pair<std::string, std::string>>;

std::vector<double> flat(const Eigen::MatrixXd& m_row_major_view) {
  std::vector<double> out;
  for (Eigen::Index r = 0; r < m_row_major_view.rows(); ++r)
    for (Eigen::Index c = 0; c < m_row_major_view.cols(); ++c) out.push_back(m_row_major_view(r, c));
  return out;
}

// The members of an .npz holding `m` as the SMPL conversion would write it.
Members smpl_members(const SmplModel& m, bool fortran_weights = false) {
  const int64_t v = m.num_vertices();
  Members members;
  members.emplace_back("v_template.npy", testing::npy({v, 3}, flat(m.v_template.transpose())));
  members.emplace_back("shapedirs.npy", testing::npy({v, 3, m.num_betas()}, flat(m.shapedirs)));
  if (m.has_posedirs())
    members.emplace_back("posedirs.npy", testing::npy({v, 3, kNumPoseFeatures}, flat(m.posedirs), "<f4"));
  members.emplace_back("J_regressor.npy", testing::npy({kNumJoints, v}, flat(Eigen::MatrixXd(m.J_regressor))));
  members.emplace_back("weights.npy",
                       testing::npy({v, kNumJoints}, flat(Eigen::MatrixXd(m.weights)), "<f8", fortran_weights));
  std::vector<double> kintree;
  for (int j = 0; j < kNumJoints; ++j) kintree.push_back(j == 0 ? 4294967295.0 : m.parents[j]);
  for (int j = 0; j < kNumJoints; ++j) kintree.push_back(j);
  members.emplace_back("kintree_table.npy", testing::npy({2, kNumJoints}, kintree, "<u4"));
  members.emplace_back("f.npy", testing::npy({m.num_faces(), 3}, flat(m.faces.cast<double>().transpose()), "<i4"));
  return members;
}

std::shared_ptr<SmplModel> load(const std::string& bytes) { return smpl_from_arrays(parse_npz(bytes, "test.npz")); }

void expect_same_model(const SmplModel& a, const SmplModel& b, double tolerance) {
  EXPECT_LT((a.v_template - b.v_template).cwiseAbs().maxCoeff(), tolerance);
  EXPECT_LT((a.shapedirs - b.shapedirs).cwiseAbs().maxCoeff(), tolerance);
  EXPECT_EQ(a.has_posedirs(), b.has_posedirs());
  if (a.has_posedirs()) {
    EXPECT_LT((a.posedirs - b.posedirs).cwiseAbs().maxCoeff(), 1e-6);  // stored as float32
  }
  EXPECT_LT((Eigen::MatrixXd(a.J_regressor) - Eigen::MatrixXd(b.J_regressor)).cwiseAbs().maxCoeff(), tolerance);
  EXPECT_LT((Eigen::MatrixXd(a.weights) - Eigen::MatrixXd(b.weights)).cwiseAbs().maxCoeff(), tolerance);
  EXPECT_EQ(a.faces, b.faces);
  EXPECT_EQ(a.parents, b.parents);
}

TEST(SmplNpz, RoundTripStoredDeflatedAndZip64) {
  const auto original = testing::random_model(3, 10, true, 11);
  for (bool deflated : {false, true})
    for (bool zip64 : {false, true}) {
      // The zip64 variant also stores the weights in Fortran order.
      const auto loaded = load(testing::zip(smpl_members(*original, zip64), deflated, zip64));
      expect_same_model(*original, *loaded, 1e-15);
    }
}

TEST(SmplNpz, LoadsFromFileAndPosesLikeTheOriginal) {
  const auto original = testing::random_model(2, 10, false, 12);
  const std::string path = (std::filesystem::temp_directory_path() / "posefuse_smpl_npz_test.npz").string();
  {
    std::ofstream out(path, std::ios::binary);
    out << testing::zip(smpl_members(*original), true);
  }
  const auto loaded = load_smpl_npz(path);
  std::filesystem::remove(path);
  const PoseLayout layout = PoseLayout::upper_body();
  BodyEvaluator a(original, layout), b(loaded, layout);
  Eigen::VectorXd theta = layout.zero();
  theta.setConstant(0.2);
  a.evaluate(Eigen::VectorXd::Ones(10), theta, Derivatives::kNone);
  b.evaluate(Eigen::VectorXd::Ones(10), theta, Derivatives::kNone);
  EXPECT_LT((a.vertices() - b.vertices()).cwiseAbs().maxCoeff(), 1e-12);
  EXPECT_FALSE(loaded->has_posedirs());
}

// Expects an Error with `code` whose field starts with `field`.
template <typename F>
void expect_error(F&& f, ErrorCode code, const std::string& field) {
  try {
    f();
    ADD_FAILURE() << "no error, expected one for " << field;
  } catch (const Error& e) {
    EXPECT_EQ(e.code(), code) << e.what();
    EXPECT_EQ(e.field().rfind(field, 0), 0u) << e.what();
  }
}

TEST(SmplNpz, EveryMissingRequiredArrayIsNamed) {
  const auto model = testing::random_model(2, 10, false, 13);
  for (const std::string key : {"v_template", "shapedirs", "J_regressor", "weights", "kintree_table", "f"}) {
    Members members = smpl_members(*model);
    std::erase_if(members, [&](const auto& m) { return m.first == key + ".npy"; });
    expect_error([&] { load(testing::zip(members, false)); }, ErrorCode::kNotFound, key);
  }
}

TEST(SmplNpz, MalformedArraysAreNamed) {
  const auto model = testing::random_model(2, 10, false, 14);
  const int64_t v = model->num_vertices();
  auto replaced = [&](const std::string& key, std::string content) {
    Members members = smpl_members(*model);
    for (auto& m : members)
      if (m.first == key + ".npy") m.second = std::move(content);
    return testing::zip(members, false);
  };
  expect_error(
      [&] {
        load(replaced("weights", testing::npy({v, 23}, std::vector<double>(v * 23, 1.0 / 23))));
      },
      ErrorCode::kInvalidArgument, "weights");
  expect_error(
      [&] {
        load(replaced("shapedirs", testing::npy({v, 10}, std::vector<double>(v * 10, 0.0))));
      },
      ErrorCode::kInvalidArgument, "shapedirs");
  expect_error(
      [&] {
        load(
            replaced("J_regressor", testing::npy({kNumJoints, v + 1}, std::vector<double>(kNumJoints * (v + 1), 0.0))));
      },
      ErrorCode::kInvalidArgument, "J_regressor");
  std::vector<double> nan_vertices(v * 3, 0.1);
  nan_vertices[7] = std::numeric_limits<double>::quiet_NaN();
  expect_error(
      [&] {
        load(replaced("v_template", testing::npy({v, 3}, nan_vertices)));
      },
      ErrorCode::kInvalidArgument, "v_template");
  expect_error(
      [&] {
        load(replaced("f", testing::npy({2, 3}, {0, 1, 2, 0, 1, 1e6}, "<i4")));
      },
      ErrorCode::kInvalidArgument, "f");
  std::vector<double> kintree(48, 0);
  for (int j = 0; j < 24; ++j) kintree[24 + j] = j;
  kintree[0] = -1;  // every joint a child of the pelvis: not SMPL's tree
  expect_error(
      [&] {
        load(replaced("kintree_table", testing::npy({2, 24}, kintree, "<i8")));
      },
      ErrorCode::kInvalidArgument, "kintree_table");
  expect_error(
      [&] {
        load(replaced("weights", testing::npy({v, 24}, std::vector<double>(v * 24, 0.0), "<c16")));
      },
      ErrorCode::kInvalidArgument, "test.npz/weights.npy.dtype");
  expect_error([&] { load(replaced("weights", "not an npy file at all")); }, ErrorCode::kDataLoss,
               "test.npz/weights.npy");
  std::string short_array = testing::npy({v, 24}, std::vector<double>(v * 24, 1.0 / 24));
  short_array.resize(short_array.size() - 9);
  expect_error([&] { load(replaced("weights", short_array)); }, ErrorCode::kDataLoss, "test.npz/weights.npy");
}

TEST(SmplNpz, DamagedArchivesAreDataLoss) {
  const auto model = testing::random_model(2, 10, false, 15);
  const std::string good = testing::zip(smpl_members(*model), true);
  expect_error([&] { load(good.substr(0, good.size() / 2)); }, ErrorCode::kDataLoss, "test.npz");
  expect_error([&] { load(good.substr(0, 10)); }, ErrorCode::kDataLoss, "test.npz");
  std::string flipped = good;
  flipped[200] = static_cast<char>(flipped[200] ^ 0x5A);  // inside the first deflated member
  expect_error([&] { load(flipped); }, ErrorCode::kDataLoss, "test.npz/v_template.npy");
  expect_error([&] { load("PK but certainly not a zip archive, no central directory here"); }, ErrorCode::kDataLoss,
               "test.npz");
  expect_error([&] { load_smpl_npz("/nonexistent/posefuse/model.npz"); }, ErrorCode::kNotFound,
               "/nonexistent/posefuse/model.npz");
}

}  // namespace
}  // namespace posefuse::body
