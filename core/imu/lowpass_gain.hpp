#pragma once
// Gain of a first-order low-pass with time constant tau for one step of dt (backward Euler:
// stable for any dt, no exp() per sample).
namespace posefuse::imu {

inline double lowpass_gain(double dt_s, double tau_s) { return dt_s / (tau_s + dt_s); }

}  // namespace posefuse::imu
