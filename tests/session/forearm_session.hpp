#pragma once
// A small synthetic session for the forearm stage, with its ground truth, from the simulator's
// pieces: the scripted right arm (sim/scripted_motion.hpp) holds the calibration pose (paper 1,
// Fig. 3b) and then moves (abduction, flexion, elbow, supination); its IMU and a static base IMU
// on the camera are simulated on their own clocks (sim/imu_device.hpp) with the buzzer stop in the
// camera audio and BLE broadcast receipts (sim/sync_signals.hpp). The camera frames are drawn
// here: a skeleton (shoulder, elbow, wrist with joint noise; INFERRED while occluded), and
// colour + depth images of the forearm as a cylinder with the black strap and of the upper arm
// as a cylinder (tests/forearm/synthetic_images.hpp); during the occlusion the strap is not drawn.
#include <cstdint>
#include <map>
#include <string>
#include <vector>

#include "forearm/forearm_types.hpp"
#include "posefuse/v1/results.pb.h"
#include "posefuse/v1/session.pb.h"

namespace posefuse::session::testing {

struct ForearmSessionOptions {
  double duration_s = 9.0;
  double hold_s = 3.0;  // calibration pose from t = motion_before_hold_s (camera clock)
  // The motion (from rest, ending at rest) for this long before the hold: a calibration pose
  // later in the session.
  double motion_before_hold_s = 0.0;
  // The whole motion with the elbow this much straighter: 0.9 rad lowers the hold's forearm to
  // 52 degrees from up, which is no calibration pose (paper 1 Fig. 3b: within 45 degrees).
  double elbow_extension_rad = 0.0;
  double occlusion_begin_s = 5.5;  // strap hidden and elbow/wrist INFERRED in [begin, end)
  double occlusion_end_s = 6.4;
  bool strap_drawn = true;       // false: the strap is never seen
  bool buzzer = true;            // false: no BUZZER_STOP event
  bool camera_alignment = true;  // false: no forearm.K_from_B option
  double joint_noise_m = 0.004;
  double calibration_s = 4.0;  // the stage option
  // Constant SDK errors of the elbow and wrist joints (a real SDK's are 5-10 cm), and the
  // stage's forearm.axis ("depth" or "sdk").
  forearm::Vec3 elbow_bias_m = forearm::Vec3::Zero();
  forearm::Vec3 wrist_bias_m = forearm::Vec3::Zero();
  std::string axis = "depth";
  // The SDK shoulder's constant error, whether the upper arm is in the depth image (a cylinder
  // from the shoulder to the elbow), and the stage's forearm.upper_arm ("depth" or "sdk").
  forearm::Vec3 shoulder_bias_m = forearm::Vec3::Zero();
  bool upper_arm_drawn = true;
  std::string upper_arm = "depth";
  double ble_repeat_s = 0.0;       // BLE bursts every this many s (0: one, at 0.5 s)
  double arm_clock_drift = 30e-6;  // the arm IMU's clock rate error (the base's is -20 ppm)
  double buzzer_tone_hz = 2700.0;  // the base IMU's buzzer
  std::string buzzer_hz_option;    // the stage's forearm.buzzer_hz; empty: not set (2700)
  std::uint64_t seed = 7;
  // The arm IMU's samples in [arm_imu_lost_from_s, + arm_imu_lost_s) camera time are lost.
  double arm_imu_lost_from_s = 0.0;
  double arm_imu_lost_s = 0.0;
  // The body fit (fit.enabled): off, since these frames hold a cylinder arm, not a body.
  bool body_fit = false;
};

struct ForearmSessionTruth {
  std::vector<std::int64_t> frame_t_us;  // camera clock
  std::vector<forearm::Vec3> imu_K;      // true IMU position per frame
  std::vector<forearm::Quat> K_from_F;   // true forearm orientation per frame
  std::vector<double> supination_rad;    // the script's supination angle per frame
  forearm::ForearmModel model;           // r, d_se, d_sw, d_ul and F_from_A
  forearm::Quat K_from_W = forearm::Quat::Identity();
  forearm::Quat K_from_F_calibration = forearm::Quat::Identity();  // the forearm in the calibration pose
  // Each IMU's clock reading at camera time 0, when both take their first sample: the true
  // camera_t - device_t there is minus this.
  std::map<std::string, std::int64_t> device_us_at_camera_zero;
  std::map<std::string, double> device_drift;  // t_device = offset + (1 + drift) t_camera
};

// Header, data chunks in approximate camera-time order, end marker.
std::vector<v1::SessionChunk> make_forearm_session(const ForearmSessionOptions& options, ForearmSessionTruth* truth);

// The forearm stage's results against the truth. Truth exists at camera frames only, so IMU
// samples and recovered samples are compared where they lie within 2 ms of a frame.
struct ForearmSessionErrors {
  std::size_t orientation_samples = 0;
  double orientation_rms_rad = 0.0, orientation_max_rad = 0.0, pronation_max_rad = 0.0;
  std::size_t pronation_nan = 0;  // samples with no pronation (no calibration pose)
  // Samples with confidence >= 0.5, those of them beyond 15 degrees and their largest error;
  // samples whose error is within the 99 % bound of their predicted RMS (1.944 u).
  std::size_t confident_samples = 0, confident_beyond_15_deg = 0, within_predicted_bound = 0;
  double confident_max_rad = 0.0;
  std::size_t frames = 0, visible_frames = 0, predicted_frames = 0;
  double visible_rms_m = 0.0, predicted_max_m = 0.0;
  // Per RecoveredSegment method (PAPER, SMOOTHER): samples compared, RMS and maximum error.
  struct Recovered {
    std::size_t samples = 0;
    double rms_m = 0.0, max_m = 0.0;
  };
  std::map<int, Recovered> recovered;
  std::size_t segments = 0;
};
// The orientation figures are the live batches' or, with `offline_solution`, the offline ones'
// (ForearmOrientationBatch.offline); the frames and segments are the same either way.
ForearmSessionErrors evaluate_forearm_results(const ForearmSessionTruth& truth,
                                              const std::vector<v1::FitResult>& results, bool offline_solution = false);

}  // namespace posefuse::session::testing
