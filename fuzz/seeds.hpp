#pragma once
// Seed inputs for the fuzz harnesses, made by code (never copied from recordings), and the
// shared entry point that writes them: a harness run with POSEFUSE_FUZZ_WRITE_SEEDS=DIR writes
// its seeds into DIR and exits instead of fuzzing (scripts/fuzz.sh does this before each run).
#include <cstdint>
#include <filesystem>
#include <functional>
#include <string>
#include <vector>

#include "posefuse/v1/session.pb.h"

namespace posefuse::fuzz {

// A small valid session: header, then every data chunk kind and encoding (depth RAW / PNG16 /
// ZSTD, body index RAW / PNG8 / ZSTD, skeleton, colour PNG / JPEG, IMU batches, audio, sync events),
// then the end marker with the right counts. It passes SessionValidator.
std::vector<v1::SessionChunk> tiny_session();
// The session's header (8x6 depth, 8x6 colour, two IMUs, 16 kHz mono audio).
v1::SessionHeader tiny_header();

// Chunks in the chunk file's length-delimited form (docs/recording-format.md).
std::string chunk_file_bytes(const std::vector<v1::SessionChunk>& chunks);

// A 16-bit PCM WAV file of `frames` sample frames.
std::string wav_bytes(std::uint16_t channels, std::uint32_t rate_hz, std::uint32_t frames);

// An encoded 8-bit or 16-bit image (cv::imencode; ext ".png" or ".jpg") of a small gradient.
std::string encoded_image(int width, int height, int cv_type, const char* ext);

// Seeds are (name, bytes) pairs.
using Seeds = std::vector<std::pair<std::string, std::string>>;

// Call from LLVMFuzzerInitialize: silences protobuf's log (invalid UTF-8 in a string field is
// logged on every parse, slowing the fuzzer tenfold) and OpenCV's; when POSEFUSE_FUZZ_WRITE_SEEDS names a
// directory, writes make_seeds() into it (one file each) and exits 0; otherwise returns.
void init_harness(const std::function<Seeds()>& make_seeds);

// A regular file in memory (memfd) holding `bytes`, positioned at its start; the decoders that
// read files take it as any recording's file. Returns the descriptor (the caller owns it).
int memory_file(const std::uint8_t* data, std::size_t size);

// Ends the process with a message: a broken decoder invariant is a finding like a crash.
[[noreturn]] void invariant_failed(const std::string& what);

}  // namespace posefuse::fuzz
