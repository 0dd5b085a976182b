#include "broad_trial.hpp"

#include <hdf5.h>

#include <cmath>
#include <cstdint>
#include <filesystem>

#include "common/error.hpp"

namespace posefuse::bench {

namespace {

// Owns one HDF5 handle; closes it with the matching H5*close function.
class Handle {
 public:
  Handle(hid_t id, herr_t (*close)(hid_t)) : id_(id), close_(close) {}
  ~Handle() {
    if (id_ >= 0) close_(id_);
  }
  Handle(const Handle&) = delete;
  Handle& operator=(const Handle&) = delete;
  hid_t get() const { return id_; }
  bool ok() const { return id_ >= 0; }

 private:
  hid_t id_;
  herr_t (*close_)(hid_t);
};

// Reads a dataset of `cols` columns (cols == 0: one-dimensional) as `mem_type` into `out`;
// returns the row count.
template <typename T>
std::size_t read_dataset(hid_t file, const std::string& path, const char* name, int cols, hid_t mem_type,
                         std::vector<T>& out) {
  const std::string field = path + ":" + name;
  if (H5Lexists(file, name, H5P_DEFAULT) <= 0) throw Error(ErrorCode::kNotFound, field, "dataset missing");
  Handle set(H5Dopen2(file, name, H5P_DEFAULT), H5Dclose);
  if (!set.ok()) throw Error(ErrorCode::kDataLoss, field, "cannot open dataset");
  Handle space(H5Dget_space(set.get()), H5Sclose);
  const int rank = H5Sget_simple_extent_ndims(space.get());
  hsize_t dims[2] = {0, 0};
  const int want_rank = cols == 0 ? 1 : 2;
  if (rank != want_rank) {
    throw_invalid(field, "has rank " + std::to_string(rank) + ", expected " + std::to_string(want_rank));
  }
  H5Sget_simple_extent_dims(space.get(), dims, nullptr);
  if (cols != 0 && dims[1] != static_cast<hsize_t>(cols)) {
    throw_invalid(field, "has " + std::to_string(dims[1]) + " columns, expected " + std::to_string(cols));
  }
  const std::size_t rows = dims[0];
  out.resize(rows * static_cast<std::size_t>(cols == 0 ? 1 : cols));
  if (rows > 0 && H5Dread(set.get(), mem_type, H5S_ALL, H5S_ALL, H5P_DEFAULT, out.data()) < 0) {
    throw Error(ErrorCode::kDataLoss, field, "read failed");
  }
  return rows;
}

double read_sampling_rate(hid_t file, const std::string& path) {
  const std::string field = path + ":sampling_rate";
  if (H5Aexists(file, "sampling_rate") <= 0) throw Error(ErrorCode::kNotFound, field, "attribute missing");
  Handle attr(H5Aopen(file, "sampling_rate", H5P_DEFAULT), H5Aclose);
  Handle space(H5Aget_space(attr.get()), H5Sclose);
  if (H5Sget_simple_extent_npoints(space.get()) != 1) throw_invalid(field, "is not a scalar");
  double rate = 0.0;
  if (H5Aread(attr.get(), H5T_NATIVE_DOUBLE, &rate) < 0) throw Error(ErrorCode::kDataLoss, field, "read failed");
  if (!std::isfinite(rate) || rate <= 0.0) throw_invalid(field, "is " + std::to_string(rate) + ", must be > 0");
  return rate;
}

void expect_rows(const std::string& path, const char* name, std::size_t rows, std::size_t n) {
  if (rows != n) {
    throw_invalid(path + ":" + name, "has " + std::to_string(rows) + " rows, imu_gyr has " + std::to_string(n));
  }
}

}  // namespace

BroadTrial read_broad_trial(const std::string& path) {
  if (!std::filesystem::is_regular_file(path)) throw Error(ErrorCode::kNotFound, path, "no such file");
  H5Eset_auto2(H5E_DEFAULT, nullptr, nullptr);  // we report errors ourselves
  Handle file(H5Fopen(path.c_str(), H5F_ACC_RDONLY, H5P_DEFAULT), H5Fclose);
  if (!file.ok()) throw Error(ErrorCode::kDataLoss, path, "not a readable HDF5 file");

  std::vector<double> gyr, acc, mag, quat;
  std::vector<std::int8_t> movement;
  const std::size_t n = read_dataset(file.get(), path, "imu_gyr", 3, H5T_NATIVE_DOUBLE, gyr);
  expect_rows(path, "imu_acc", read_dataset(file.get(), path, "imu_acc", 3, H5T_NATIVE_DOUBLE, acc), n);
  expect_rows(path, "imu_mag", read_dataset(file.get(), path, "imu_mag", 3, H5T_NATIVE_DOUBLE, mag), n);
  expect_rows(path, "opt_quat", read_dataset(file.get(), path, "opt_quat", 4, H5T_NATIVE_DOUBLE, quat), n);
  expect_rows(path, "movement", read_dataset(file.get(), path, "movement", 0, H5T_NATIVE_INT8, movement), n);

  BroadTrial trial;
  trial.name = std::filesystem::path(path).stem().string();
  trial.sampling_rate_hz = read_sampling_rate(file.get(), path);
  trial.imu.resize(n);
  trial.ENU_from_sensor_gt.resize(n);
  trial.movement.resize(n);
  const double period_us = 1e6 / trial.sampling_rate_hz;
  for (std::size_t i = 0; i < n; ++i) {
    imu::ImuSample& s = trial.imu[i];
    s.t_us = std::llround(static_cast<double>(i) * period_us);
    s.gyr_rad_s = geometry::Vec3(gyr[3 * i], gyr[3 * i + 1], gyr[3 * i + 2]);
    s.acc_m_s2 = geometry::Vec3(acc[3 * i], acc[3 * i + 1], acc[3 * i + 2]);
    s.mag_uT = geometry::Vec3(mag[3 * i], mag[3 * i + 1], mag[3 * i + 2]);
    trial.ENU_from_sensor_gt[i] = geometry::Quat(quat[4 * i], quat[4 * i + 1], quat[4 * i + 2], quat[4 * i + 3]);
    trial.movement[i] = movement[i] != 0;
  }
  return trial;
}

}  // namespace posefuse::bench
