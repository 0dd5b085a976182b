#pragma once
// Sound-based synchronisation (paper 1, II-G.1): the base IMU stops its buzzer at a time it
// records on its own clock; the camera's microphone hears the tone stop. The stop time on the
// camera clock, minus the base IMU's recorded stop time, is the clock offset base IMU -> camera.
#include <cstdint>
#include <vector>

namespace posefuse::sync {

// Mono signed 16-bit PCM recorded by the camera; sample n was taken at
// t0_camera_us + n * 1e6 / sample_rate_hz on the camera clock.
struct AudioPcm {
  double t0_camera_us = 0.0;
  double sample_rate_hz = 0.0;
  std::vector<std::int16_t> samples;
};

struct BuzzerStopOptions {
  double tone_hz = 2700.0;           // buzzer fundamental; must be below the Nyquist frequency
  double window_s = 0.005;           // envelope window (rounded to whole tone periods); the edge ramp
                                     // lasts one window, so shorter is sharper but noisier
  double min_on_s = 0.05;            // the tone must have sounded at least this long before stopping
  double min_off_s = 0.05;           // and stay silent at least this long afterwards
  double min_on_to_off_ratio = 4.0;  // tone envelope / silence envelope; below this: no event
};

struct BuzzerStop {
  double t_camera_us = 0.0;  // where the tone stopped, camera clock, sub-sample
  double sigma_us = 0.0;     // 1-sigma: envelope noise on the edge, the sample grid, and the
                             // tone-phase-dependent mirror-frequency bias (see .cpp)
  double on_level = 0.0;     // envelope amplitude of the tone (PCM units)
  double off_level = 0.0;    // envelope amplitude after the stop (noise floor)
};

// Finds the last stop of a tone at `tone_hz` in the audio: quadrature demodulation at the tone
// frequency, a centred moving-average envelope over a whole number of tone periods followed by a
// half-period box (a step in amplitude becomes a ramp centred on the step), then a least-squares
// line through the ramp between 25% and 75% of the tone level, solved for the half level.
// Throws posefuse::Error: kInvalidArgument for a bad rate, tone or empty audio ("audio.*",
// "options.*"); kFailedPrecondition "audio.buzzer" when no tone stop is found.
BuzzerStop detect_buzzer_stop(const AudioPcm& audio, const BuzzerStopOptions& options = {});

// A clock observation: the same instant read on a device clock and on a reference clock.
struct ClockObservation {
  double device_us = 0.0;
  double reference_us = 0.0;
  double sigma_us = 0.0;  // 1-sigma of reference_us - device_us
};

// The buzzer stop as an observation base IMU -> camera (offset = t_camera - t_base).
// `base_stop_sigma_us` is the uncertainty of the base IMU's own stop timestamp and of the
// buzzer's electrical-to-acoustic delay; it adds in quadrature to the audio edge sigma.
ClockObservation buzzer_observation(const BuzzerStop& stop, double base_stop_device_us, double base_stop_sigma_us);

}  // namespace posefuse::sync
