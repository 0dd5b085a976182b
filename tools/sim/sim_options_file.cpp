#include "tools/sim/sim_options_file.hpp"

#include <charconv>
#include <cmath>
#include <functional>
#include <map>
#include <set>

#include "common/error.hpp"
#include "session/file_bytes.hpp"

namespace posefuse::tools {
namespace {

constexpr double kDegree = 3.14159265358979323846 / 180.0;
using Options = sim::SimSessionOptions;

[[noreturn]] void bad(const std::string& field, const std::string& value, const std::string& why) {
  throw Error(ErrorCode::kInvalidArgument, field, "value '" + value + "' " + why);
}

double number(const std::string& value, const std::string& field) {
  double out = 0;
  const char* end = value.data() + value.size();
  const auto [ptr, ec] = std::from_chars(value.data(), end, out);
  if (ec != std::errc() || ptr != end || !std::isfinite(out)) bad(field, value, "is not a finite number");
  return out;
}
double positive(const std::string& value, const std::string& field) {
  const double x = number(value, field);
  if (x <= 0) bad(field, value, "must be > 0");
  return x;
}
double non_negative(const std::string& value, const std::string& field) {
  const double x = number(value, field);
  if (x < 0) bad(field, value, "must be >= 0");
  return x;
}
double probability(const std::string& value, const std::string& field) {
  const double x = number(value, field);
  if (x < 0 || x > 1) bad(field, value, "must be in [0, 1]");
  return x;
}
long long integer(const std::string& value, const std::string& field, long long low, long long high) {
  long long out = 0;
  const char* end = value.data() + value.size();
  const auto [ptr, ec] = std::from_chars(value.data(), end, out);
  if (ec != std::errc() || ptr != end) bad(field, value, "is not an integer");
  if (out < low || out > high) {
    bad(field, value, "must be in " + std::to_string(low) + ".." + std::to_string(high));
  }
  return out;
}
bool boolean(const std::string& value, const std::string& field) {
  if (value == "true" || value == "on" || value == "1") return true;
  if (value == "false" || value == "off" || value == "0") return false;
  bad(field, value, "is not a boolean (true/false, on/off, 1/0)");
}

struct Setter {
  const char* meaning;
  std::function<void(Options&, const std::string&, const std::string&)> apply;
};

const std::map<std::string, Setter>& setters() {
  static const std::map<std::string, Setter> table = {
      {"seed", {"random seed (unsigned 64-bit); every random part derives its stream from it",
                [](Options& o, const std::string& v, const std::string& f) {
                  std::uint64_t out = 0;
                  const auto [ptr, ec] = std::from_chars(v.data(), v.data() + v.size(), out);
                  if (ec != std::errc() || ptr != v.data() + v.size()) bad(f, v, "is not an unsigned integer");
                  o.seed = out;
                }}},
      {"duration_s", {"session length, 1..3600 s, or clip: the motion's own length (the whole BVH clip, or the exercise)",
                      [](Options& o, const std::string& v, const std::string& f) {
                        o.duration_from_motion = v == "clip";
                        if (o.duration_from_motion) return;
                        o.duration_s = number(v, f);
                        if (o.duration_s < 1 || o.duration_s > 3600) bad(f, v, "must be in 1..3600 or clip");
                      }}},
      {"motion", {"an exercise (arm_raising, forearm_protocol, ... see exercises.hpp) or bvh (arm_raising)",
                  [](Options& o, const std::string& v, const std::string& f) {
                    const auto names = sim::motion_names();
                    if (std::find(names.begin(), names.end(), v) == names.end()) bad(f, v, "is not a known motion");
                    o.motion = v;
                  }}},
      {"bvh_path", {"motion bvh: the BVH file to play (relative to the working directory)",
                    [](Options& o, const std::string& v, const std::string&) { o.motion_options.bvh_path = v; }}},
      {"bvh_smoothing", {"motion bvh: gaussian (0.03 s) or noise_level (a smoothing spline per channel matched to its own noise) (gaussian)",
                         [](Options& o, const std::string& v, const std::string& f) {
                           if (v == "gaussian") o.motion_options.bvh_smoothing = sim::BvhSmoothing::kGaussian;
                           else if (v == "noise_level") o.motion_options.bvh_smoothing = sim::BvhSmoothing::kNoiseLevel;
                           else bad(f, v, "must be gaussian or noise_level");
                         }}},
      {"bvh_joint_map", {"motion bvh: which BVH joint drives which SMPL joint: auto (by name), mocap21, cmu31, or a joint-map file (relative to the working directory) (auto)",
                         [](Options& o, const std::string& v, const std::string&) {
                           o.motion_options.bvh_joint_map = sim::bvh_joint_map_named(v);
                         }}},
      {"bvh_max_glitch_frames", {"motion bvh: longest mocap glitch repaired by interpolation, frames, 1..600 (12)",
                                 [](Options& o, const std::string& v, const std::string& f) {
                                   o.motion_options.bvh_glitches.max_glitch_frames = static_cast<int>(integer(v, f, 1, 600));
                                 }}},
      {"bvh_max_joint_rate_rad_s", {"motion bvh: a joint turning faster than this relative to its parent is a glitch, rad/s, 10..1000 (60)",
                                    [](Options& o, const std::string& v, const std::string& f) {
                                      const double rate = number(v, f);
                                      if (rate < 10 || rate > 1000) bad(f, v, "must be in 10..1000");
                                      o.motion_options.bvh_glitches.max_joint_rate_rad_s = rate;
                                    }}},
      {"calibration_prefix", {"motion bvh: paper 1's calibration pose (with arm) before the clip, blended in (false)",
                              [](Options& o, const std::string& v, const std::string& f) {
                                o.motion_options.calibration_prefix = boolean(v, f);
                              }}},
      {"calibration_suffix", {"motion bvh: paper 1's calibration pose (with arm) after the clip, blended in (false)",
                              [](Options& o, const std::string& v, const std::string& f) {
                                o.motion_options.calibration_suffix = boolean(v, f);
                              }}},
      {"speed", {"playback speed factor of the exercise or BVH clip, > 0; 2 halves every movement and hold (1)",
                 [](Options& o, const std::string& v, const std::string& f) {
                   o.motion_options.exercise.speed = positive(v, f);
                 }}},
      {"repetitions", {"exercise repetitions, 1..1000 (3)", [](Options& o, const std::string& v, const std::string& f) {
                         o.motion_options.exercise.repetitions = static_cast<int>(integer(v, f, 1, 1000));
                       }}},
      {"arm", {"exercising arm: right, left or both (right)", [](Options& o, const std::string& v, const std::string& f) {
                 if (v == "right") o.motion_options.exercise.arm = sim::ExerciseArm::kRight;
                 else if (v == "left") o.motion_options.exercise.arm = sim::ExerciseArm::kLeft;
                 else if (v == "both") o.motion_options.exercise.arm = sim::ExerciseArm::kBoth;
                 else bad(f, v, "must be right, left or both");
               }}},
      {"sex", {"male or female (the built-in template)", [](Options& o, const std::string& v, const std::string& f) {
                 if (v == "male") o.sex = body::Sex::kMale;
                 else if (v == "female") o.sex = body::Sex::kFemale;
                 else bad(f, v, "must be male or female");
               }}},
      {"betas", {"up to 10 comma-separated shape coefficients", [](Options& o, const std::string& v, const std::string& f) {
                   std::vector<double> values;
                   std::size_t begin = 0;
                   while (begin <= v.size()) {
                     const std::size_t comma = std::min(v.find(',', begin), v.size());
                     std::string item = v.substr(begin, comma - begin);
                     item.erase(0, item.find_first_not_of(" \t"));
                     item.erase(item.find_last_not_of(" \t") + 1);
                     values.push_back(number(item, f));
                     begin = comma + 1;
                   }
                   if (values.size() > body::kTemplateNumBetas) bad(f, v, "has more than 10 values");
                   o.betas = Eigen::VectorXd::Zero(body::kTemplateNumBetas);
                   for (std::size_t i = 0; i < values.size(); ++i) o.betas[static_cast<Eigen::Index>(i)] = values[i];
                 }}},
      {"heading_deg", {"subject's facing from magnetic north towards west, deg",
                       [](Options& o, const std::string& v, const std::string& f) { o.heading_rad = number(v, f) * kDegree; }}},
      {"depth_rate_hz", {"depth / body index / skeleton / colour rate, Hz (1..120)",
                         [](Options& o, const std::string& v, const std::string& f) {
                           o.depth_rate_hz = positive(v, f);
                           if (o.depth_rate_hz > 120) bad(f, v, "must be at most 120");
                         }}},
      {"camera_height_m", {"camera above the floor, m (0.3..2.5)", [](Options& o, const std::string& v, const std::string& f) {
                             o.camera_height_m = positive(v, f);
                             if (o.camera_height_m < 0.3 || o.camera_height_m > 2.5) bad(f, v, "must be in 0.3..2.5");
                           }}},
      {"camera_pitch_deg", {"camera pitched down (> 0) or up, deg (-30..30) (0)",
                            [](Options& o, const std::string& v, const std::string& f) {
                              o.camera_pitch_deg = number(v, f);
                              if (std::abs(o.camera_pitch_deg) > 30) bad(f, v, "must be in -30..30");
                            }}},
      {"camera_roll_deg", {"camera rolled about its view, its top towards its left (> 0), deg (-20..20) (0)",
                           [](Options& o, const std::string& v, const std::string& f) {
                             o.camera_roll_deg = number(v, f);
                             if (std::abs(o.camera_roll_deg) > 20) bad(f, v, "must be in -20..20");
                           }}},
      {"subject_distance_m", {"camera to subject, m (1..4)", [](Options& o, const std::string& v, const std::string& f) {
                                o.subject_distance_m = positive(v, f);
                                if (o.subject_distance_m < 1 || o.subject_distance_m > 4) bad(f, v, "must be in 1..4");
                              }}},
      {"wall_distance_m", {"camera to the back wall, m (> subject_distance_m + 0.5)",
                           [](Options& o, const std::string& v, const std::string& f) { o.wall_distance_m = positive(v, f); }}},
      {"color", {"render the colour stream (true/false)",
                 [](Options& o, const std::string& v, const std::string& f) { o.color = boolean(v, f); }}},
      {"color_width", {"colour image width, px (64..1920); height, fx, fy, cx, cy scale with it (16:9)",
                       [](Options& o, const std::string& v, const std::string& f) {
                         const auto w = integer(v, f, 64, 1920);
                         const double s = static_cast<double>(w) / 1920.0;
                         auto& in = o.color_camera.intrinsics;
                         in.width = static_cast<int>(w);
                         in.height = static_cast<int>(std::lround(1080 * s));
                         in.fx = in.fy = 1056.0 * s;
                         in.cx = 0.5 * in.width - 0.5;
                         in.cy = 0.5 * in.height - 0.5;
                       }}},
      {"color_noise_sigma", {"colour noise per channel, of 255", [](Options& o, const std::string& v, const std::string& f) {
                               o.color_camera.noise_sigma = non_negative(v, f);
                             }}},
      {"color_jpeg_quality", {"JPEG quality 1..100", [](Options& o, const std::string& v, const std::string& f) {
                                o.color_camera.jpeg_quality = static_cast<int>(integer(v, f, 1, 100));
                              }}},
      {"strap_width_m", {"strap band width along the forearm, m", [](Options& o, const std::string& v, const std::string& f) {
                           o.color_camera.strap_width_m = positive(v, f);
                         }}},
      {"record_height", {"the header records the subject's standing height (true/false)",
                         [](Options& o, const std::string& v, const std::string& f) { o.record_height = boolean(v, f); }}},
      {"height_error_m", {"error of the recorded height, 1 sigma, m (<= 0.1)",
                          [](Options& o, const std::string& v, const std::string& f) {
                            o.height_error_m = non_negative(v, f);
                            if (o.height_error_m > 0.1) bad(f, v, "must be at most 0.1");
                          }}},
      {"clothing", {"clothing / soft-tissue offsets on (true/false)",
                    [](Options& o, const std::string& v, const std::string& f) { o.clothing.enabled = boolean(v, f); }}},
      {"clothing_subdivisions", {"template subdivision levels for rendering, 0..2",
                                 [](Options& o, const std::string& v, const std::string& f) {
                                   o.clothing.subdivisions = static_cast<int>(integer(v, f, 0, 2));
                                 }}},
      {"clothing_torso_offset_m", {"largest offset on the torso, m (<= 0.1)",
                                   [](Options& o, const std::string& v, const std::string& f) {
                                     o.clothing.torso_offset_m = non_negative(v, f);
                                     if (o.clothing.torso_offset_m > 0.1) bad(f, v, "must be at most 0.1");
                                   }}},
      {"clothing_sleeve_offset_m", {"largest offset on the upper arms, m (<= 0.1)",
                                    [](Options& o, const std::string& v, const std::string& f) {
                                      o.clothing.sleeve_offset_m = non_negative(v, f);
                                      if (o.clothing.sleeve_offset_m > 0.1) bad(f, v, "must be at most 0.1");
                                    }}},
      {"clothing_skin_offset_m", {"largest soft-tissue offset on forearms, hands, head, m (<= 0.1)",
                                  [](Options& o, const std::string& v, const std::string& f) {
                                    o.clothing.skin_offset_m = non_negative(v, f);
                                    if (o.clothing.skin_offset_m > 0.1) bad(f, v, "must be at most 0.1");
                                  }}},
      {"soft_tissue_wobble", {"soft-tissue wobble of the rendered surface under fast motion on (true/false)",
                              [](Options& o, const std::string& v, const std::string& f) {
                                o.soft_tissue.enabled = boolean(v, f);
                              }}},
      {"soft_tissue_max_m", {"largest soft-tissue wobble of any vertex, m (<= 0.1)",
                             [](Options& o, const std::string& v, const std::string& f) {
                               o.soft_tissue.max_displacement_m = non_negative(v, f);
                               if (o.soft_tissue.max_displacement_m > 0.1) bad(f, v, "must be at most 0.1");
                             }}},
      {"panel_capture", {"also write calibration_capture/: the calibration panel seen by mocap, IR/depth and IMUs (false)",
                         [](Options& o, const std::string& v, const std::string& f) {
                           o.panel_capture.enabled = boolean(v, f);
                         }}},
      {"panel_poses", {"calibration panel poses, 1..20 (4)", [](Options& o, const std::string& v, const std::string& f) {
                         o.panel_capture.poses = static_cast<int>(integer(v, f, 1, 20));
                       }}},
      {"panel_marker_noise_m", {"mocap marker noise per axis, m (0.0003)",
                                [](Options& o, const std::string& v, const std::string& f) {
                                  o.panel_capture.marker_noise_m = non_negative(v, f);
                                }}},
      {"panel_imu_misalignment_deg", {"panel IMU's visual alignment on the panel, per-axis sigma, deg (0.5)",
                                      [](Options& o, const std::string& v, const std::string& f) {
                                        o.panel_capture.imu_misalignment_deg = non_negative(v, f);
                                      }}},
      {"imu_arms", {"arms with an IMU: both, left, right or none", [](Options& o, const std::string& v, const std::string& f) {
                      if (v == "both") o.arm_imu = {true, true};
                      else if (v == "left") o.arm_imu = {true, false};
                      else if (v == "right") o.arm_imu = {false, true};
                      else if (v == "none") o.arm_imu = {false, false};
                      else bad(f, v, "must be both, left, right or none");
                    }}},
      {"imu_roles_swapped", {"the header names each arm IMU for the other arm (false)",
                             [](Options& o, const std::string& v, const std::string& f) {
                               o.arm_imu_roles_swapped = boolean(v, f);
                             }}},
      {"strap_to_elbow_m", {"d_se: strap centre to elbow, m", [](Options& o, const std::string& v, const std::string& f) {
                              o.strap_to_elbow_m = positive(v, f);
                            }}},
      {"strap_radius_m", {"r: forearm axis to the IMU, m", [](Options& o, const std::string& v, const std::string& f) {
                            o.strap_radius_m = positive(v, f);
                          }}},
      {"mount_sigma_deg", {"random IMU mounting F_from_A, per-axis sigma, deg",
                           [](Options& o, const std::string& v, const std::string& f) {
                             o.mount_sigma_rad = non_negative(v, f) * kDegree;
                           }}},
      {"strap_slip", {"strap slip on (true/false)",
                      [](Options& o, const std::string& v, const std::string& f) { o.strap_slip.enabled = boolean(v, f); }}},
      {"strap_slip_max_deg", {"largest slip turn about the forearm, deg", [](Options& o, const std::string& v, const std::string& f) {
                                o.strap_slip.max_rotation_rad = non_negative(v, f) * kDegree;
                              }}},
      {"strap_slip_max_slide_m", {"largest slide along the forearm, m", [](Options& o, const std::string& v, const std::string& f) {
                                    o.strap_slip.max_slide_m = non_negative(v, f);
                                  }}},
      {"imu_rate_hz", {"IMU rate on each device's clock, Hz (10..1000)", [](Options& o, const std::string& v, const std::string& f) {
                         o.imu.rate_hz = positive(v, f);
                         if (o.imu.rate_hz < 10 || o.imu.rate_hz > 1000) bad(f, v, "must be in 10..1000");
                       }}},
      {"gyro_range_dps", {"gyroscope full scale per axis, deg/s (125..4000); beyond it the reading clips (2000)",
                          [](Options& o, const std::string& v, const std::string& f) {
                            const double dps = number(v, f);
                            if (dps < 125 || dps > 4000) bad(f, v, "must be in 125..4000");
                            o.imu.synth.gyr_range_rad_s = dps * kDegree;
                          }}},
      {"acc_range_g", {"accelerometer full scale per axis, g = 9.80665 m/s^2 (2..32); beyond it the reading clips (16)",
                       [](Options& o, const std::string& v, const std::string& f) {
                         const double g = number(v, f);
                         if (g < 2 || g > 32) bad(f, v, "must be in 2..32");
                         o.imu.synth.acc_range_m_s2 = g * sim::kStandardGravity_m_s2;
                       }}},
      {"imu_warm_up_K", {"each IMU warms by this many K from its first sample (0..20; 0: none), its biases with it",
                         [](Options& o, const std::string& v, const std::string& f) {
                           const double kelvin = non_negative(v, f);
                           if (kelvin > 20) bad(f, v, "must be in 0..20");
                           o.imu.synth.warm_up.rise_K = kelvin;
                         }}},
      {"imu_warm_up_time_constant_s", {"time constant of the IMUs' warm-up, s (1..3600; 300)",
                                       [](Options& o, const std::string& v, const std::string& f) {
                                         const double seconds = number(v, f);
                                         if (seconds < 1 || seconds > 3600) bad(f, v, "must be in 1..3600");
                                         o.imu.synth.warm_up.time_constant_s = seconds;
                                       }}},
      {"imu_errors", {"IMU error model on (true) or ideal signals (false)",
                      [](Options& o, const std::string& v, const std::string& f) {
                        o.imu.synth.error_model = boolean(v, f) ? sim::ImuErrorModel() : sim::ImuErrorModel::none();
                      }}},
      {"packet_loss_rate", {"fraction of IMU packets lost, [0, 0.5]", [](Options& o, const std::string& v, const std::string& f) {
                              o.imu.packet_loss.loss_rate = probability(v, f);
                              if (o.imu.packet_loss.loss_rate > 0.5) bad(f, v, "must be at most 0.5");
                            }}},
      {"clock_offset_max_s", {"device clock offsets drawn in [1, this] s", [](Options& o, const std::string& v, const std::string& f) {
                                o.clock_offset_max_s = number(v, f);
                                if (o.clock_offset_max_s < 1) bad(f, v, "must be >= 1");
                              }}},
      {"clock_drift_max_ppm", {"device clock drifts drawn in [-this, this] ppm (< 1000)",
                               [](Options& o, const std::string& v, const std::string& f) {
                                 const double ppm = non_negative(v, f);
                                 if (ppm >= 1000) bad(f, v, "must be below 1000");
                                 o.clock_drift_max = ppm * 1e-6;
                               }}},
      {"ble_repeat_s", {"BLE broadcast bursts every this many s through the session (0: one at the start, paper 1)",
                        [](Options& o, const std::string& v, const std::string& f) {
                          o.ble.repeat_every_s = non_negative(v, f);
                          if (o.ble.repeat_every_s > 0 && o.ble.repeat_every_s < 1) bad(f, v, "must be 0 or >= 1");
                        }}},
      {"buzzer_repeat_s", {"the buzzer stops again every this many s through the session (0: once, paper 1)",
                           [](Options& o, const std::string& v, const std::string& f) {
                             o.buzzer_repeat_s = non_negative(v, f);
                             if (o.buzzer_repeat_s > 0 && o.buzzer_repeat_s < 2) bad(f, v, "must be 0 or >= 2");
                           }}},
      {"skeleton_jump_probability", {"camera skeleton jumps per frame, [0, 1]",
                                     [](Options& o, const std::string& v, const std::string& f) {
                                       o.skeleton.jump_probability = probability(v, f);
                                     }}},
      {"buzzer_tone_hz", {"the buzzer's frequency, Hz, 200..7900 (2700; the server measures it within 10 % of forearm.buzzer_hz, or anywhere with auto)",
                          [](Options& o, const std::string& v, const std::string& f) {
                            o.buzzer.tone_hz = positive(v, f);
                            if (o.buzzer.tone_hz < 200 || o.buzzer.tone_hz > 7900) bad(f, v, "must be in [200, 7900] Hz");
                          }}},
      {"buzzer_stop_s", {"buzzer stop on the camera clock, s (clamped to 0.6 x duration)",
                         [](Options& o, const std::string& v, const std::string& f) { o.buzzer_stop_s = positive(v, f); }}},
      {"audio_rate_hz", {"microphone rate, 16000 or 48000", [](Options& o, const std::string& v, const std::string& f) {
                           const auto rate = integer(v, f, 0, 1000000);
                           if (rate != 16000 && rate != 48000) bad(f, v, "must be 16000 or 48000");
                           o.audio.sample_rate_hz = static_cast<std::uint32_t>(rate);
                         }}},
      {"threads", {"frames rendered in parallel, 1..64 (output does not depend on it)",
                   [](Options& o, const std::string& v, const std::string& f) { o.threads = static_cast<int>(integer(v, f, 1, 64)); }}},
  };
  return table;
}

std::string trim(const std::string& s) {
  const auto begin = s.find_first_not_of(" \t\r");
  if (begin == std::string::npos) return "";
  return s.substr(begin, s.find_last_not_of(" \t\r") - begin + 1);
}

}  // namespace

const std::vector<SimOptionKey>& sim_option_keys() {
  static const std::vector<SimOptionKey> keys = [] {
    std::vector<SimOptionKey> out;
    for (const auto& [key, setter] : setters()) out.push_back(SimOptionKey{key.c_str(), setter.meaning});
    return out;
  }();
  return keys;
}

void apply_sim_option(const std::string& key, const std::string& value, const std::string& field,
                      sim::SimSessionOptions& options) {
  const auto it = setters().find(key);
  if (it == setters().end()) {
    throw Error(ErrorCode::kInvalidArgument, field, "unknown key '" + key + "' (see docs/simulator.md)");
  }
  it->second.apply(options, value, field);
}

void apply_sim_options(const std::string& text, const std::string& name, sim::SimSessionOptions& options) {
  std::set<std::string> seen;
  std::size_t line_number = 0;
  std::size_t begin = 0;
  while (begin < text.size()) {
    const std::size_t end = std::min(text.find('\n', begin), text.size());
    std::string line = text.substr(begin, end - begin);
    begin = end + 1;
    ++line_number;
    const auto hash = line.find('#');
    if (hash != std::string::npos) line.erase(hash);
    line = trim(line);
    if (line.empty()) continue;
    const std::string where = name + ":" + std::to_string(line_number);
    const auto equals = line.find('=');
    if (equals == std::string::npos) {
      throw Error(ErrorCode::kInvalidArgument, where, "expected 'key = value', got '" + line + "'");
    }
    const std::string key = trim(line.substr(0, equals));
    const std::string value = trim(line.substr(equals + 1));
    if (key.empty()) throw Error(ErrorCode::kInvalidArgument, where, "empty key in '" + line + "'");
    if (value.empty()) throw Error(ErrorCode::kInvalidArgument, where + ":" + key, "has no value");
    if (!seen.insert(key).second) throw Error(ErrorCode::kInvalidArgument, where + ":" + key, "is set twice");
    apply_sim_option(key, value, where + ":" + key, options);
  }
}

void apply_sim_options_file(const std::filesystem::path& path, sim::SimSessionOptions& options) {
  apply_sim_options(session::read_file_bytes(path, path.string()), path.string(), options);
}

}  // namespace posefuse::tools
