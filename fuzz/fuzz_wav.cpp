// The WAV reader (session/wav.*, a recording directory's audio.wav) on arbitrary file bytes,
// read as the directory reader reads it (a regular file through FdInputStream). Every sample
// frame the header announces is read in pieces; the header may not announce more data than
// the file holds.
#include <algorithm>
#include <cstddef>
#include <cstdint>
#include <memory>

#include "common/error.hpp"
#include "seeds.hpp"
#include "session/recording_file.hpp"
#include "session/wav.hpp"

using namespace posefuse;

extern "C" int LLVMFuzzerInitialize(int*, char***) {
  fuzz::init_harness([] {
    std::string with_list = fuzz::wav_bytes(1, 16'000, 20);
    // A LIST chunk before fmt (odd size, so a pad byte follows), as some writers emit.
    with_list.insert(12, std::string("LIST\x03\0\0\0abc\0", 12));
    return fuzz::Seeds{{"mono.wav", fuzz::wav_bytes(1, 16'000, 40)},
                       {"stereo.wav", fuzz::wav_bytes(2, 48'000, 10)},
                       {"list.wav", with_list}};
  });
  return 0;
}

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  try {
    session::UniqueFd file(fuzz::memory_file(data, size));
    session::WavReader wav(std::make_unique<session::FdInputStream>(std::move(file)), size, "audio.wav");
    const std::uint64_t frame_bytes = 2ull * wav.format().channels;
    if (wav.total_frames() * frame_bytes > size) fuzz::invariant_failed("more audio than file");
    while (wav.frames_left() > 0) {
      const std::uint64_t n = std::min<std::uint64_t>(wav.frames_left(), 4096);
      if (wav.read_frames(n).size() != n * frame_bytes) fuzz::invariant_failed("short read");
    }
  } catch (const Error&) {
  }
  return 0;
}
