#pragma once
// Minimal RIFF/WAVE support for the directory form's audio.wav: PCM, signed 16-bit,
// little-endian, interleaved channels (WAVE_FORMAT_PCM, the 44-byte canonical layout on write).
#include <cstdint>
#include <filesystem>
#include <fstream>
#include <istream>
#include <memory>
#include <string>

namespace posefuse::session {

struct WavFormat {
  std::uint32_t sample_rate_hz = 0;
  std::uint16_t channels = 0;
};

// Streams sample frames out of a WAV file. Unknown RIFF chunks (LIST, fact, ...) are skipped.
class WavReader {
 public:
  // kNotFound if the file cannot be opened; kInvalidArgument (field = `name`) for a file that
  // is not 16-bit PCM WAVE; kDataLoss when the data chunk is shorter than its header says.
  WavReader(const std::filesystem::path& path, std::string name);
  // Reads an already open stream of `file_size` bytes (a recording's file opened beneath its
  // directory).
  WavReader(std::unique_ptr<std::istream> in, std::uint64_t file_size, std::string name);

  const WavFormat& format() const { return format_; }
  std::uint64_t total_frames() const { return total_frames_; }
  std::uint64_t frames_left() const { return total_frames_ - frames_read_; }

  // Next `frames` sample frames as interleaved s16le bytes; kDataLoss if fewer are left.
  std::string read_frames(std::uint64_t frames);

 private:
  void read_header(std::uint64_t file_size);

  std::unique_ptr<std::istream> in_;
  std::string name_;
  WavFormat format_;
  std::uint64_t total_frames_ = 0;
  std::uint64_t frames_read_ = 0;
};

// Writes a WAV file as sample frames arrive; the RIFF sizes are patched in finish().
class WavWriter {
 public:
  WavWriter(const std::filesystem::path& path, WavFormat format);
  // `pcm_s16le` must hold whole frames (a multiple of 2 * channels bytes).
  void write_frames(const std::string& pcm_s16le);
  void finish();
  const WavFormat& format() const { return format_; }

 private:
  std::filesystem::path path_;
  std::ofstream out_;
  WavFormat format_;
  std::uint64_t data_bytes_ = 0;
};

}  // namespace posefuse::session
