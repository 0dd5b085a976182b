#pragma once
// Reader for one BROAD trial (HDF5; layout in ../shared/data/broad/README.md).
#include <string>
#include <vector>

#include "geometry/quaternion.hpp"
#include "imu/imu_sample.hpp"

namespace posefuse::bench {

struct BroadTrial {
  std::string name;  // file name without ".hdf5"
  double sampling_rate_hz = 0.0;
  std::vector<imu::ImuSample> imu;                 // timestamps built from the sampling rate, from t = 0
  std::vector<geometry::Quat> ENU_from_sensor_gt;  // optical ground truth; NaN where lost
  std::vector<bool> movement;                      // errors are counted only where true
};

// Reads imu_gyr, imu_acc, imu_mag (N x 3), opt_quat (N x 4, [w x y z]), movement (N) and the
// attribute sampling_rate. Throws posefuse::Error naming the file and dataset for a missing
// file or dataset, a wrong shape or a bad sampling rate.
BroadTrial read_broad_trial(const std::string& path);

}  // namespace posefuse::bench
