#include "fit/frame_fitter.hpp"

#include <algorithm>
#include <cmath>
#include <optional>
#include <span>
#include <string>

#include "common/error.hpp"
#include "fit/camera_projection.hpp"

namespace posefuse::fit {
namespace {

// Throws "field" unless every index lies in [0, size) and none repeats.
void check_distinct_indices(std::span<const int> indices, int size, const std::string& field) {
  std::vector<bool> seen(static_cast<size_t>(size), false);
  for (int i : indices) {
    if (i < 0 || i >= size || seen[static_cast<size_t>(i)])
      throw_invalid(field,
                    "index " + std::to_string(i) + " is out of range [0, " + std::to_string(size) + ") or repeated");
    seen[static_cast<size_t>(i)] = true;
  }
}

// A model point on the visible contour sees itself along its ray up to this gap: grazing rays
// meet the neighbouring faces of the vertex a little before it.
constexpr double kContourVisibilityTolerance_m = 0.01;
// Points closer to the camera plane than this are not projected.
constexpr double kMinDepth_m = 0.05;

// The bg target of a point projecting to `pixel` (options.silhouette_edge_px), or nullopt when the
// point projects inside the silhouette or outside the image: the image shows nothing there, so a
// body cut by the image's edge (feet below a camera that looks up) is not pulled into the view.
std::optional<Eigen::Vector2d> silhouette_target(const SilhouetteDistanceMap& silhouette, const Eigen::Vector2d& pixel,
                                                 double edge_px) {
  const long col = std::lround(pixel.x()), row = std::lround(pixel.y());
  const bool in_image = col >= 0 && row >= 0 && col < silhouette.width && row < silhouette.height;
  if (!in_image || silhouette.distance_px[static_cast<size_t>(row) * silhouette.width + col] == 0) return std::nullopt;
  const Eigen::Vector2d centre = silhouette.closest(pixel.x(), pixel.y());
  const Eigen::Vector2d offset = pixel - centre;
  const double distance = offset.norm();
  if (distance <= edge_px) return std::nullopt;
  return centre + (edge_px / distance) * offset;
}

}  // namespace

const char* fit_status_name(FitStatus status) {
  switch (status) {
    case FitStatus::kConverged: return "converged";
    case FitStatus::kMaxIterations: return "max_iterations";
  }
  return "unknown";
}

FrameFitter::FrameFitter(std::shared_ptr<const body::SmplModel> model, body::PoseLayout layout,
                         const raycast::DepthIntrinsics& intrinsics, const FitOptions& options)
    : model_((validate(options), raycast::validate(intrinsics), std::move(model))),
      layout_(std::move(layout)),
      intrinsics_(intrinsics),
      options_(options),
      eval_(model_, layout_),
      trial_eval_(model_, layout_),
      surface_(model_->faces, model_->num_vertices()),
      trial_surface_(model_->faces, model_->num_vertices()),
      scene_(raycast::EmbreeDevice::shared(), model_->faces, model_->num_vertices()),
      discrete_(*model_, options_) {
  point_jacobian_.setZero(3, layout_.size());
  data_jacobian_.setZero(6, layout_.size());
  packed_data_jacobian_.setZero(6, layout_.size());
  data_shape_jacobian_.setZero(6, model_->num_betas());
}

void FrameFitter::adopt_trial() {
  // Swapping contents keeps each object's address (SurfacePoseJacobians keys on the evaluator's).
  std::swap(eval_, trial_eval_);
  std::swap(surface_, trial_surface_);
  scene_.update_vertices(eval_.vertices());
}

void FrameFitter::split(const Eigen::VectorXd& x, Eigen::VectorXd& theta, Eigen::VectorXd& beta) const {
  const int n = layout_.size();
  theta = x.head(n);
  for (size_t b = 0; b < free_betas_.size(); ++b) beta[free_betas_[b]] = x[n + static_cast<Eigen::Index>(b)];
}

const Eigen::MatrixXd& FrameFitter::joint_jacobian() const {
  return free_betas_.empty() ? eval_.joint_pose_jacobian() : joint_jacobian_;
}

void FrameFitter::vertex_jacobian(int i, Eigen::Ref<Eigen::Matrix3Xd> out) const {
  out.setZero();
  eval_.add_vertex_pose_jacobian(i, 1.0, out.leftCols(layout_.size()));
  if (free_betas_.empty()) return;
  const auto shape = eval_.vertex_shape_jacobian(i);
  for (size_t b = 0; b < free_betas_.size(); ++b)
    out.col(layout_.size() + static_cast<Eigen::Index>(b)) = shape.col(free_betas_[b]);
}

double FrameFitter::shape_bound_energy(const Eigen::VectorXd& beta) const {
  if (free_betas_.empty()) return 0.0;
  Eigen::VectorXd free(static_cast<Eigen::Index>(free_betas_.size()));
  for (size_t b = 0; b < free_betas_.size(); ++b) free[static_cast<Eigen::Index>(b)] = beta[free_betas_[b]];
  const double prior = prior_matrix_.rows() > 0 ? (prior_matrix_ * beta - prior_target_).squaredNorm() : 0.0;
  return shape_bound_.energy(free) + prior;
}

void FrameFitter::set_up_blocks(const FrameObservation& o) {
  const size_t n = o.points_K.size();
  const double sqrt_n = std::sqrt(static_cast<double>(n));
  data_.resize(n);
  for (size_t i = 0; i < n; ++i)
    data_[i] = {o.points_K[i], o.normals_K[i], 1 / (options_.sigma_p_m * sqrt_n), 1 / (options_.sigma_n * sqrt_n)};
  imu_.clear();
  const double imu_weight = std::sqrt(options_.lambda_imu);
  if (o.forearm.left_K && o.forearm.left_weight > 0)
    imu_.push_back(
        {body::kLeftElbow, body::kLeftWrist, *o.forearm.left_K, imu_weight * std::sqrt(o.forearm.left_weight)});
  if (o.forearm.right_K && o.forearm.right_weight > 0)
    imu_.push_back(
        {body::kRightElbow, body::kRightWrist, *o.forearm.right_K, imu_weight * std::sqrt(o.forearm.right_weight)});
  const int limited = LimitResidual::size(layout_);
  limit_.weight = limited > 0 ? std::sqrt(options_.lambda_limit / limited) : 0.0;
  const int free = static_cast<int>(free_betas_.size());
  shape_bound_.weight = free > 0 ? std::sqrt(options_.lambda_limit / free) : 0.0;
  // Largest residual count: every set at its cap (data rows live in the residual vector only).
  // (A U_bg point is a bg or a float residual: at most 3 rows, the float offset of the shape fit.)
  const int max_rows = 6 * static_cast<int>(n) + 3 * options_.max_bg_points + 2 * kBgJointCount + limited + free +
                       static_cast<int>(prior_matrix_.rows()) + 6;
  const int p = num_parameters();
  if (jacobian_.rows() < max_rows || jacobian_.cols() != p) jacobian_.resize(max_rows, p);
  if (residual_.size() < max_rows) residual_.resize(max_rows);
  if (point_jacobian_.cols() != p) point_jacobian_.setZero(3, p);
  if (data_jacobian_.cols() != p) data_jacobian_.setZero(6, p);
  uv_jacobian_.resize(n);
}

void FrameFitter::pose_model(const Eigen::VectorXd& theta, const Eigen::VectorXd& beta) {
  // The vertices' pose Jacobians follow in linearise(), for the vertices the residuals use.
  eval_.evaluate(beta, theta,
                 free_betas_.empty() ? body::Derivatives::kPoseOnRequest : body::Derivatives::kPoseAndShape);
  surface_.update(eval_.vertices());
  scene_.update_vertices(eval_.vertices());
  if (free_betas_.empty()) return;
  const int n = layout_.size();
  joint_jacobian_.resize(3 * body::kNumJoints, num_parameters());
  joint_jacobian_.leftCols(n) = eval_.joint_pose_jacobian();
  for (size_t b = 0; b < free_betas_.size(); ++b)
    joint_jacobian_.col(n + static_cast<Eigen::Index>(b)) = eval_.joint_shape_jacobian().col(free_betas_[b]);
}

void FrameFitter::init_correspondences(const FrameObservation& o) {
  // Start from the model point on each sample's camera ray, or the closest model point where the
  // ray misses the model; then the discrete update as in every iteration.
  scene_.first_hits(o.points_K, hits_);
  correspondences_.resize(o.points_K.size());
  for (size_t i = 0; i < hits_.size(); ++i) {
    const raycast::ClosestPoint hit = hits_[i].face >= 0 ? hits_[i] : scene_.closest_point(o.points_K[i]);
    correspondences_[i] = {hit.face, hit.u, hit.v};
  }
  update_correspondences(o, 0);
}

void FrameFitter::update_correspondences(const FrameObservation& o, int iteration) {
  if (!options_.discrete_update) return;
  scene_.first_hits(o.points_K, hits_);
  hit_points_.resize(hits_.size());
  for (size_t i = 0; i < hits_.size(); ++i) hit_points_[i] = {hits_[i].face, hits_[i].u, hits_[i].v};
  const SampleTargets targets{&o.points_K, &o.normals_K, 1 / (options_.sigma_p_m * options_.sigma_p_m),
                              1 / (options_.sigma_n * options_.sigma_n)};
  discrete_.update(surface_, targets, hit_points_, iteration, correspondences_);
}

void FrameFitter::select_point_sets(const FrameObservation& o) {
  const Eigen::Matrix3Xd& vertices = eval_.vertices();
  const Eigen::Matrix3Xd& normals = surface_.vertex_normals();
  // U_bg (eq. 6): visible vertices whose normal is nearly perpendicular to the viewing ray.
  contour_vertices_.clear();
  for (int v = 0; v < vertices.cols(); ++v) {
    const Eigen::Vector3d p = vertices.col(v);
    if (p.z() < kMinDepth_m) continue;
    if (std::abs(normals.col(v).dot(p.normalized())) <= options_.bg_contour_max_cos) contour_vertices_.push_back(v);
  }
  contour_points_.resize(3, static_cast<Eigen::Index>(contour_vertices_.size()));
  for (size_t k = 0; k < contour_vertices_.size(); ++k)
    contour_points_.col(static_cast<Eigen::Index>(k)) = vertices.col(contour_vertices_[k]);
  const std::vector<bool> visible = scene_.visible(contour_points_, kContourVisibilityTolerance_m);
  selected_.clear();
  for (size_t k = 0; k < contour_vertices_.size(); ++k)
    if (visible[k]) selected_.push_back(contour_vertices_[k]);
  // At most H_max points, spread evenly over the contour (vertex order follows the body parts).
  if (static_cast<int>(selected_.size()) > options_.max_bg_points) {
    const double stride = static_cast<double>(selected_.size()) / options_.max_bg_points;
    for (int k = 0; k < options_.max_bg_points; ++k) selected_[k] = selected_[static_cast<size_t>(k * stride)];
    selected_.resize(static_cast<size_t>(options_.max_bg_points));
  }
  bg_weight_ = selected_.empty() ? 0.0 : std::sqrt(options_.lambda_bg / static_cast<double>(selected_.size()));
  // Q (eq. 12) is counted here and kept for the iteration, like H.
  build_blocks(eval_, o);
  float_weight_ = float_.empty() ? 0.0 : std::sqrt(options_.lambda_float / static_cast<double>(float_.size()));
  for (BehindPoint& f : float_) f.block.weight = float_weight_;
}

void FrameFitter::build_blocks(const body::BodyEvaluator& eval, const FrameObservation& o) {
  // The sets' members stay fixed within an iteration; whether each is outside the silhouette
  // (bg), inside but in front of the surface (float) or neither, and its D_2D / D_3D target, are
  // taken at the pose being evaluated, so a trial step that pushes other contour points out of
  // the silhouette pays for it.
  bg_.clear();
  float_.clear();
  for (int v : selected_) {
    const Eigen::Vector3d p = eval.vertices().col(v);
    if (p.z() < kMinDepth_m) continue;
    const Eigen::Vector2d pixel = project_with_jacobian(intrinsics_, p).pixel;
    if (const auto target = silhouette_target(o.silhouette, pixel, options_.silhouette_edge_px)) {
      bg_.push_back({v, {*target, bg_weight_}});
    } else if (!o.behind->is_behind(p)) {
      // U_float (eq. 12) is the part of U_bg inside the silhouette but in front of the surface.
      float_.push_back({v, {o.behind->closest_behind(p, behind_cache_), float_weight_}});
    }
  }
  // bgJoint (eq. 7): joints that project outside the silhouette.
  bg_joint_.clear();
  const double joint_weight = std::sqrt(options_.lambda_bg_joint / kBgJointCount);
  for (int j : kBgJoints) {
    const Eigen::Vector3d p = eval.joints().col(j);
    if (p.z() < kMinDepth_m) continue;
    const Eigen::Vector2d pixel = project_with_jacobian(intrinsics_, p).pixel;
    if (const auto target = silhouette_target(o.silhouette, pixel, options_.silhouette_edge_px))
      bg_joint_.push_back({j, {*target, joint_weight}});
  }
}

void FrameFitter::compute_used_vertex_jacobians() {
  if (!free_betas_.empty()) return;  // pose_model evaluated them all (kPoseAndShape)
  const auto& faces = surface_.faces();
  used_.resize(static_cast<size_t>(model_->num_vertices()), 0);
  used_vertices_.clear();
  const auto use = [&](int v) {
    if (used_[static_cast<size_t>(v)]) return;
    used_[static_cast<size_t>(v)] = 1;
    used_vertices_.push_back(v);
  };
  // The data term: each correspondence's corners and, where the vertex normal's Jacobian needs
  // them, their 1-rings.
  for (const body::SurfacePoint& c : correspondences_)
    for (int k = 0; k < 3; ++k) {
      const int v = faces(k, c.face);
      use(v);
      if (!surface_jacobians_.normal_needs_ring(v)) continue;
      for (int f : surface_.faces_of_vertex(v))
        for (int corner = 0; corner < 3; ++corner) use(faces(corner, f));
    }
  // The bg and float points build_blocks() chose from U_bg (the rest of U_bg has no residual).
  for (const SilhouettePoint& s : bg_) use(s.index);
  for (const BehindPoint& f : float_) use(f.vertex);
  eval_.compute_vertex_pose_jacobians(used_vertices_);
  for (int v : used_vertices_) used_[static_cast<size_t>(v)] = 0;
}

EnergyTerms FrameFitter::linearise(const FrameObservation& o, const Eigen::VectorXd& theta,
                                   const Eigen::VectorXd& beta) {
  build_blocks(eval_, o);
  surface_jacobians_.reset(surface_, eval_);
  compute_used_vertex_jacobians();
  const int n = static_cast<int>(data_.size());
  const int N = layout_.size();
  const int free = static_cast<int>(free_betas_.size());
  EnergyTerms e;
  system_.reset(num_parameters(), n);
  int row = 0;
  auto take = [&](int count, double& energy) {
    energy += residual_.segment(row, count).squaredNorm();
    row += count;
  };
  for (int i = 0; i < n; ++i) {
    // The data rows go straight into the normal equations, packed over the DOFs that move the
    // sample's face (SurfacePoseJacobians::face_columns).
    const std::span<const int> columns = surface_jacobians_.face_columns(correspondences_[i].face);
    const int m = static_cast<int>(columns.size());
    data_[i].evaluate_packed(surface_, eval_, surface_jacobians_, correspondences_[i], residual_.segment<6>(row),
                             packed_data_jacobian_.leftCols(m), uv_jacobian_[i]);
    if (free == 0) {
      system_.add_block(i, columns, packed_data_jacobian_.leftCols(m), uv_jacobian_[i], residual_.segment<6>(row));
    } else {  // III-B: the shape columns are dense
      data_jacobian_.setZero();
      for (int c = 0; c < m; ++c) data_jacobian_.col(columns[static_cast<size_t>(c)]) = packed_data_jacobian_.col(c);
      data_[i].evaluate_shape(surface_, eval_, correspondences_[i], data_shape_jacobian_);
      for (int b = 0; b < free; ++b)
        data_jacobian_.col(N + b) = data_shape_jacobian_.col(free_betas_[static_cast<size_t>(b)]);
      system_.add_block(i, data_jacobian_, uv_jacobian_[i], residual_.segment<6>(row));
    }
    take(6, e.data);
  }
  const int pose_rows_begin = row;
  // bg, bgJoint and float as offsets to held targets, or (pose fit, FitOptions::linearise_distances)
  // as distances (SilhouetteResidual).
  const bool offsets = free > 0 || !options_.linearise_distances;
  const auto add_silhouette = [&](const SilhouetteResidual& block, const Eigen::Vector3d& x,
                                  const Eigen::Ref<const PoseRows3>& d_x, double& energy) {
    if (offsets) {
      block.evaluate_offset(intrinsics_, x, d_x, residual_.segment<2>(row), jacobian_.middleRows(row, 2));
      take(2, energy);
    } else {
      block.evaluate(intrinsics_, x, d_x, residual_[row], jacobian_.middleRows(row, 1));
      take(1, energy);
    }
  };
  for (const SilhouettePoint& s : bg_) {
    vertex_jacobian(s.index, point_jacobian_);
    add_silhouette(s.block, eval_.vertices().col(s.index), point_jacobian_, e.bg);
  }
  for (const SilhouettePoint& s : bg_joint_)
    add_silhouette(s.block, eval_.joints().col(s.index), joint_jacobian().middleRows<3>(3 * s.index), e.bg_joint);
  for (const BehindPoint& f : float_) {
    vertex_jacobian(f.vertex, point_jacobian_);
    if (offsets) {
      f.block.evaluate_offset(eval_.vertices().col(f.vertex), point_jacobian_, residual_.segment<3>(row),
                              jacobian_.middleRows(row, 3));
      take(3, e.float_term);
    } else {
      f.block.evaluate(eval_.vertices().col(f.vertex), point_jacobian_, residual_[row], jacobian_.middleRows(row, 1));
      take(1, e.float_term);
    }
  }
  const int limited = LimitResidual::size(layout_);
  limit_.evaluate(layout_, theta, residual_.segment(row, limited), jacobian_.middleRows(row, limited));
  // Only DOFs beyond their limits have a residual (and a Jacobian row): drop the zero rows, they
  // add nothing to the normal equations but their share of its rank update.
  int active = 0;
  for (int k = 0; k < limited; ++k)
    if (residual_[row + k] != 0) {
      residual_[row + active] = residual_[row + k];
      jacobian_.row(row + active) = jacobian_.row(row + k);
      ++active;
    }
  take(active, e.limit);
  if (free > 0) {
    free_beta_values_.resize(free);
    for (int b = 0; b < free; ++b) free_beta_values_[b] = beta[free_betas_[static_cast<size_t>(b)]];
    jacobian_.middleRows(row, free).leftCols(N).setZero();
    shape_bound_.evaluate(free_beta_values_, residual_.segment(row, free),
                          jacobian_.middleRows(row, free).rightCols(free));
    take(free, e.shape);
    const int k = static_cast<int>(prior_matrix_.rows());
    if (k > 0) {
      residual_.segment(row, k) = prior_matrix_ * beta - prior_target_;
      jacobian_.middleRows(row, k).leftCols(N).setZero();
      for (int b = 0; b < free; ++b)
        jacobian_.middleRows(row, k).col(N + b) = prior_matrix_.col(free_betas_[static_cast<size_t>(b)]);
      take(k, e.shape);
    }
  }
  for (const ForearmDirectionResidual& f : imu_) {
    f.evaluate(eval_.joints(), joint_jacobian(), residual_.segment<3>(row), jacobian_.middleRows(row, 3));
    take(3, e.imu);
  }
  system_.add_pose_rows(jacobian_.middleRows(pose_rows_begin, row - pose_rows_begin),
                        residual_.segment(pose_rows_begin, row - pose_rows_begin));
  return e;
}

EnergyTerms FrameFitter::energy_at(const FrameObservation& o, const body::BodyEvaluator& eval,
                                   const body::BodySurface& surface,
                                   const std::vector<body::SurfacePoint>& correspondences, const Eigen::VectorXd& theta,
                                   const Eigen::VectorXd& beta) {
  build_blocks(eval, o);
  EnergyTerms e;
  for (size_t i = 0; i < data_.size(); ++i) e.data += data_[i].residual(surface, correspondences[i]).squaredNorm();
  for (const SilhouettePoint& s : bg_) e.bg += s.block.offset(intrinsics_, eval.vertices().col(s.index)).squaredNorm();
  for (const SilhouettePoint& s : bg_joint_)
    e.bg_joint += s.block.offset(intrinsics_, eval.joints().col(s.index)).squaredNorm();
  for (const BehindPoint& f : float_) e.float_term += f.block.offset(eval.vertices().col(f.vertex)).squaredNorm();
  e.limit = limit_.energy(layout_, theta);
  e.shape = shape_bound_energy(beta);
  for (const ForearmDirectionResidual& f : imu_) e.imu += f.residual(eval.joints()).squaredNorm();
  return e;
}

FitResult FrameFitter::fit(const FrameObservation& observation, const Eigen::VectorXd& theta0,
                           const Eigen::VectorXd& beta, std::span<const int> held_dofs) {
  clear_shape_freedom();
  check_distinct_indices(held_dofs, layout_.size(), "held_dofs");
  std::vector<int> held(held_dofs.begin(), held_dofs.end());
  std::sort(held.begin(), held.end());
  return run(observation, theta0, beta, held);
}

FitResult FrameFitter::fit_shape_and_pose(const FrameObservation& observation, const Eigen::VectorXd& theta0,
                                          const Eigen::VectorXd& beta0, const ShapeFreedom& freedom) {
  const int num_betas = model_->num_betas();
  if (!(freedom.max_abs_beta > 0) || !std::isfinite(freedom.max_abs_beta))
    throw_invalid("shape_freedom.max_abs_beta", std::to_string(freedom.max_abs_beta) + " is not a positive number");
  std::vector<int> free = freedom.free_betas;
  if (free.empty())
    for (int b = 0; b < num_betas; ++b) free.push_back(b);
  check_distinct_indices(free, num_betas, "shape_freedom.free_betas");
  if (layout_.size() + static_cast<int>(free.size()) > SchurSystem::kMaxPose)
    throw_invalid("shape_freedom.free_betas", "too many parameters for the solver");
  const Eigen::Index k = freedom.prior_matrix.rows();
  if ((k > 0 && freedom.prior_matrix.cols() != num_betas) || freedom.prior_target.size() != k ||
      !freedom.prior_matrix.allFinite() || !freedom.prior_target.allFinite())
    throw_invalid("shape_freedom.prior_matrix", std::to_string(k) + " x " +
                                                    std::to_string(freedom.prior_matrix.cols()) + " with a target of " +
                                                    std::to_string(freedom.prior_target.size()) + ", expected k x " +
                                                    std::to_string(num_betas) + " and k, finite");
  free_betas_ = std::move(free);
  shape_bound_.bound = freedom.max_abs_beta;
  prior_matrix_ = freedom.prior_matrix;
  prior_target_ = freedom.prior_target;
  try {
    FitResult result = run(observation, theta0, beta0);
    clear_shape_freedom();
    return result;
  } catch (...) {
    clear_shape_freedom();  // the next fit() must not inherit the shape columns
    throw;
  }
}

void FrameFitter::project_onto_limits(const Eigen::VectorXd& x, Eigen::VectorXd& trial_x) const {
  // The limit term is zero inside the range, so the Gauss-Newton model does not see it: a DOF the
  // data hardly constrain (an arm hidden behind the back) gets a step of radians across its limit,
  // where eq. 8's penalty then dominates the trial's energy. A DOF within the margin of its range
  // stays within it; one already further out may move but not further out.
  const double m = options_.limit_projection_margin_rad;
  for (int d = 0; d < layout_.size(); ++d) {
    const body::Dof& dof = layout_.dof(d);
    if (!dof.limited) continue;
    trial_x[d] = std::clamp(trial_x[d], std::min(dof.min_rad - m, x[d]), std::max(dof.max_rad + m, x[d]));
  }
}

FitResult FrameFitter::run(const FrameObservation& observation, const Eigen::VectorXd& theta0,
                           const Eigen::VectorXd& beta0, std::span<const int> held) {
  validate(observation);
  FitResult result;
  set_up_blocks(observation);
  Eigen::VectorXd theta = theta0;
  pose_model(theta, beta0);  // checks theta and beta
  // The full beta (padded to the model's size) and the LM parameters x = (theta, beta_free).
  Eigen::VectorXd beta = Eigen::VectorXd::Zero(model_->num_betas());
  beta.head(beta0.size()) = beta0;
  const int n = layout_.size();
  Eigen::VectorXd x(num_parameters());
  x.head(n) = theta;
  for (size_t b = 0; b < free_betas_.size(); ++b) x[n + static_cast<Eigen::Index>(b)] = beta[free_betas_[b]];
  trial_beta_ = beta;
  init_correspondences(observation);
  select_point_sets(observation);
  result.initial_energy = energy_at(observation, eval_, surface_, correspondences_, theta, beta);

  double gamma = options_.initial_damping;
  double raise = options_.damping_increase;
  // From freeze_contour_after on U_bg stays as selected then (FitOptions::freeze_contour_after);
  // the shape fit (III-B, once per session, far from its start) keeps re-selecting it.
  const auto frozen = [&](int iteration) {
    return free_betas_.empty() && options_.freeze_contour_after > 0 && iteration >= options_.freeze_contour_after;
  };
  for (int iteration = 0; iteration < options_.max_iterations; ++iteration) {
    if (iteration > 0 && !frozen(iteration)) select_point_sets(observation);
    const double energy_before = linearise(observation, theta, beta).total();
    ++result.iterations;
    double energy_after = energy_before, joint_step = 0;
    bool accepted = false;
    while (gamma <= options_.max_damping) {
      if (system_.solve(gamma, step_, uv_step_, held)) {
        trial_x_ = x + step_;
        if (options_.project_steps_onto_limits) {
          project_onto_limits(x, trial_x_);
          step_ = trial_x_ - x;
        }
        split(trial_x_, trial_theta_, trial_beta_);
        // With the shape fixed the trial is evaluated as pose_model() would: an accepted trial
        // becomes the current model by a swap (adopt_trial) instead of a second evaluation.
        trial_eval_.evaluate(trial_beta_, trial_theta_,
                             free_betas_.empty() ? body::Derivatives::kPoseOnRequest : body::Derivatives::kNone);
        trial_surface_.update(trial_eval_.vertices());
        trial_correspondences_.resize(correspondences_.size());
        // II-I: the correspondences follow their (du, dv) over face borders.
        for (size_t i = 0; i < correspondences_.size(); ++i)
          trial_correspondences_[i] = trial_surface_.walk(correspondences_[i], uv_step_[i].x(), uv_step_[i].y()).end;
        energy_after =
            energy_at(observation, trial_eval_, trial_surface_, trial_correspondences_, trial_theta_, trial_beta_)
                .total();
        joint_step = 0;
        for (int j : kBgJoints)
          joint_step = std::max(joint_step, (trial_eval_.joints().col(j) - eval_.joints().col(j)).norm());
        if (energy_after < energy_before) {
          accepted = true;
          break;
        }
        ++result.rejected_steps;
        // Damping has shrunk the step below the convergence motion without finding a decrease:
        // more damping would only shrink it further.
        if (joint_step < options_.min_joint_step_m) break;
      }
      gamma *= raise;
      raise *= 2;
    }
    if (!accepted) {  // no step lowers the energy: a (local) minimum
      result.status = FitStatus::kConverged;
      break;
    }
    ++result.accepted_steps;
    // The joint-step stop below asks whether the body still moves; a step shrunk by damping raised
    // above joint_step_stop_max_damping says nothing about that (FitOptions).
    const bool step_undamped = gamma <= options_.joint_step_stop_max_damping;
    // Gain ratio (Nielsen): how well the quadratic model predicted the decrease.
    const double predicted = system_.predicted_decrease(gamma, step_, uv_step_);
    const double rho = predicted > 0 ? (energy_before - energy_after) / predicted : 0.0;
    gamma = std::max(gamma * std::max(options_.damping_decrease, 1 - std::pow(2 * rho - 1, 3)), 1e-12);
    raise = options_.damping_increase;
    x = trial_x_;
    theta = trial_theta_;
    beta = trial_beta_;
    std::swap(correspondences_, trial_correspondences_);
    if (free_betas_.empty()) adopt_trial();
    else pose_model(theta, beta);
    update_correspondences(observation, iteration + 1);
    if (energy_before - energy_after < options_.min_relative_decrease * energy_before ||
        (joint_step < options_.min_joint_step_m && step_undamped)) {
      result.status = FitStatus::kConverged;
      break;
    }
  }
  select_point_sets(observation);
  result.energy = energy_at(observation, eval_, surface_, correspondences_, theta, beta);
  result.theta = theta;
  result.beta = beta;
  result.correspondences = correspondences_;
  return result;
}

EnergyTerms FrameFitter::energy(const FrameObservation& observation, const Eigen::VectorXd& theta,
                                const Eigen::VectorXd& beta) {
  validate(observation);
  clear_shape_freedom();
  set_up_blocks(observation);
  pose_model(theta, beta);
  init_correspondences(observation);
  select_point_sets(observation);
  return energy_at(observation, eval_, surface_, correspondences_, theta, beta);
}

}  // namespace posefuse::fit
