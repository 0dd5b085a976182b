#include "session/wav.hpp"

#include <array>

#include "common/error.hpp"

namespace posefuse::session {

namespace {

constexpr std::uint16_t kFormatPcm = 1;
constexpr std::uint16_t kBitsPerSample = 16;
// A RIFF size field is 32 bits: the data chunk can hold at most this many bytes.
constexpr std::uint64_t kMaxDataBytes = 0xFFFFFFFFull - 36;

std::uint32_t le32(const char* p) {
  std::uint32_t v = 0;
  for (int i = 3; i >= 0; --i) v = (v << 8) | static_cast<unsigned char>(p[i]);
  return v;
}
std::uint16_t le16(const char* p) {
  return static_cast<std::uint16_t>(static_cast<unsigned char>(p[0]) | (static_cast<unsigned char>(p[1]) << 8));
}
void put_le32(std::ostream& out, std::uint32_t v) {
  for (int i = 0; i < 4; ++i) out.put(static_cast<char>((v >> (8 * i)) & 0xFF));
}
void put_le16(std::ostream& out, std::uint16_t v) {
  out.put(static_cast<char>(v & 0xFF));
  out.put(static_cast<char>(v >> 8));
}

}  // namespace

WavReader::WavReader(const std::filesystem::path& path, std::string name)
    : in_(std::make_unique<std::ifstream>(path, std::ios::binary)), name_(std::move(name)) {
  if (!*in_) throw Error(ErrorCode::kNotFound, name_, "cannot open " + path.string());
  read_header(static_cast<std::uint64_t>(std::filesystem::file_size(path)));
}

WavReader::WavReader(std::unique_ptr<std::istream> in, std::uint64_t file_size, std::string name)
    : in_(std::move(in)), name_(std::move(name)) {
  read_header(file_size);
}

void WavReader::read_header(std::uint64_t file_size) {
  std::array<char, 12> riff{};
  if (!in_->read(riff.data(), riff.size()) || std::string(riff.data(), 4) != "RIFF" ||
      std::string(riff.data() + 8, 4) != "WAVE") {
    throw_invalid(name_, "is not a RIFF/WAVE file");
  }
  bool have_format = false;
  std::uint64_t position = 12;
  while (true) {
    std::array<char, 8> chunk{};
    if (!in_->read(chunk.data(), chunk.size())) {
      throw_invalid(name_, have_format ? "has no data chunk" : "has no fmt chunk");
    }
    position += 8;
    const std::string id(chunk.data(), 4);
    const std::uint32_t size = le32(chunk.data() + 4);
    if (id == "fmt ") {
      if (size < 16) throw_invalid(name_ + ".fmt", "fmt chunk is too short");
      std::array<char, 16> fmt{};
      in_->read(fmt.data(), fmt.size());
      const std::uint16_t tag = le16(fmt.data());
      format_.channels = le16(fmt.data() + 2);
      format_.sample_rate_hz = le32(fmt.data() + 4);
      const std::uint16_t bits = le16(fmt.data() + 14);
      if (tag != kFormatPcm || bits != kBitsPerSample) {
        throw_invalid(name_ + ".fmt", "format tag " + std::to_string(tag) + " with " + std::to_string(bits) +
                                          " bits per sample; only 16-bit PCM (tag 1) is supported");
      }
      if (format_.channels == 0 || format_.sample_rate_hz == 0) {
        throw_invalid(name_ + ".fmt", "zero channels or zero sample rate");
      }
      have_format = true;
    } else if (id == "data") {
      if (!have_format) throw_invalid(name_, "data chunk comes before the fmt chunk");
      const std::uint64_t frame_bytes = 2ull * format_.channels;
      if (size % frame_bytes != 0) {
        throw_invalid(name_ + ".data", "size " + std::to_string(size) + " is not a whole number of sample frames");
      }
      if (position + size > file_size) {
        throw Error(
            ErrorCode::kDataLoss, name_ + ".data",
            "header says " + std::to_string(size) + " bytes, the file holds " + std::to_string(file_size - position));
      }
      total_frames_ = size / frame_bytes;
      return;  // positioned at the first sample
    }
    // Skip this chunk (and its pad byte: RIFF chunks are word-aligned).
    const std::uint64_t skip = size + (size & 1u);
    position += skip;
    in_->seekg(static_cast<std::streamoff>(position));
  }
}

std::string WavReader::read_frames(std::uint64_t frames) {
  if (frames > frames_left()) {
    throw Error(
        ErrorCode::kDataLoss, name_ + ".data",
        "asked for " + std::to_string(frames) + " sample frames, only " + std::to_string(frames_left()) + " left");
  }
  std::string bytes(frames * 2 * format_.channels, '\0');
  in_->read(bytes.data(), static_cast<std::streamsize>(bytes.size()));
  if (static_cast<std::uint64_t>(in_->gcount()) != bytes.size()) {
    throw Error(ErrorCode::kDataLoss, name_ + ".data", "file ends early");
  }
  frames_read_ += frames;
  return bytes;
}

WavWriter::WavWriter(const std::filesystem::path& path, WavFormat format)
    : path_(path), out_(path, std::ios::binary | std::ios::trunc), format_(format) {
  if (!out_) throw_precondition(path.string(), "cannot create file");
  if (format.channels == 0 || format.sample_rate_hz == 0) {
    throw_invalid(path.string(), "zero channels or zero sample rate");
  }
  const std::uint16_t block_align = static_cast<std::uint16_t>(2 * format.channels);
  out_.write("RIFF", 4);
  put_le32(out_, 36);  // patched in finish()
  out_.write("WAVEfmt ", 8);
  put_le32(out_, 16);
  put_le16(out_, kFormatPcm);
  put_le16(out_, format.channels);
  put_le32(out_, format.sample_rate_hz);
  put_le32(out_, format.sample_rate_hz * block_align);
  put_le16(out_, block_align);
  put_le16(out_, kBitsPerSample);
  out_.write("data", 4);
  put_le32(out_, 0);  // patched in finish()
}

void WavWriter::write_frames(const std::string& pcm_s16le) {
  if (pcm_s16le.size() % (2u * format_.channels) != 0) {
    throw_invalid(path_.string(),
                  "PCM byte count " + std::to_string(pcm_s16le.size()) + " is not a whole number of sample frames");
  }
  if (data_bytes_ + pcm_s16le.size() > kMaxDataBytes) {
    throw Error(ErrorCode::kResourceExhausted, path_.string(), "audio exceeds the 4 GiB WAV limit");
  }
  out_.write(pcm_s16le.data(), static_cast<std::streamsize>(pcm_s16le.size()));
  data_bytes_ += pcm_s16le.size();
}

void WavWriter::finish() {
  out_.seekp(4);
  put_le32(out_, static_cast<std::uint32_t>(36 + data_bytes_));
  out_.seekp(40);
  put_le32(out_, static_cast<std::uint32_t>(data_bytes_));
  out_.close();
  if (!out_) throw Error(ErrorCode::kDataLoss, path_.string(), "write failed");
}

}  // namespace posefuse::session
