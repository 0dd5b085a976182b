#pragma once
// Which tone is the buzzer's? For a clinic whose buzzer is not the usual 2700 Hz piezo, the
// frequency is found in the audio itself (stage option forearm.buzzer_hz = auto).
//
// The buzzer is the loudest narrowband sound in the band that both sounds and stops within the
// audio: short-time spectra (Hann window, frames of a power of two samples, no overlap) give for
// every frequency bin its level while loudest (the third-loudest frame, so that one click does not
// count) and while quietest; a bin qualifies when the first exceeds the second by
// min_on_to_off_ratio (amplitude) and the loud frame's peak stands min_peak_to_band_ratio above
// the bins 4-12 away from it (a tone, not broadband noise or speech's wide formants). Of the
// qualifying bins the loudest wins; its frequency is refined by a parabola through the log power
// of the three bins around the peak, averaged over the frames where the tone sounds. With 20 ms
// frames the bins are 50 Hz wide and the refined frequency is within a few Hz: the stop detector
// (buzzer_stop.hpp) demodulates over 5 ms, where an error of 10 Hz turns the phase by 18 degrees.
#include <optional>

#include "sync/buzzer_stop.hpp"

namespace posefuse::sync {

struct ToneSearchOptions {
  double min_hz = 500.0;                // piezo buzzers sound at 2-4 kHz; mains hum lies below
  double max_hz = 8000.0;               // and at most the Nyquist frequency of the audio
  double frame_s = 0.02;                // rounded up to a power of two samples (at least 64)
  double min_on_to_off_ratio = 4.0;     // amplitude, as BuzzerStopOptions
  double min_peak_to_band_ratio = 4.0;  // amplitude, the loud frame's peak against its neighbourhood
};

struct FoundTone {
  double hz = 0.0;
  double on_to_off_ratio = 0.0;     // amplitude: loudest (third-loudest frame) / quietest frame
  double peak_to_band_ratio = 0.0;  // amplitude
};

// Throws posefuse::Error kInvalidArgument "audio.sample_rate_hz" or "options" for a bad rate or
// options (min_hz >= max_hz, min_hz at or above the Nyquist frequency, frame_s or a ratio).
void validate_tone_search(const ToneSearchOptions& options, double sample_rate_hz);

// nullopt when no tone in [min_hz, max_hz] both sounds and stops in the audio (or the audio is
// shorter than four frames). Throws as validate_tone_search.
std::optional<FoundTone> find_stopping_tone(const AudioPcm& audio, const ToneSearchOptions& options = {});

}  // namespace posefuse::sync
