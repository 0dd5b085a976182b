// SessionValidator (session/session_validator.*) on a decoded SessionChunk stream: the input
// is read as a chunk file's length-delimited chunks (protobuf's CodedInputStream, so most
// mutations still give a stream of parseable chunks), and every chunk is checked as the
// pipeline checks it: a bad data chunk is skipped, a bad header or end marker ends the stream.
// An accepted depth or body index chunk must hand on an image of the header's depth size.
#include <cstddef>
#include <cstdint>

#include <google/protobuf/io/coded_stream.h>

#include "common/error.hpp"
#include "seeds.hpp"
#include "session/session_validator.hpp"

using namespace posefuse;

extern "C" int LLVMFuzzerInitialize(int*, char***) {
  fuzz::init_harness([] {
    const auto session = fuzz::tiny_session();
    fuzz::Seeds seeds{{"session", fuzz::chunk_file_bytes(session)}};
    // Each data chunk alone after the header, so that mutations stay close to one kind.
    for (std::size_t i = 1; i + 1 < session.size(); ++i) {
      seeds.push_back({"chunk-" + std::to_string(i), fuzz::chunk_file_bytes({session.front(), session[i]})});
    }
    return seeds;
  });
  return 0;
}

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  google::protobuf::io::CodedInputStream in(data, static_cast<int>(size));
  session::SessionValidator validator;
  v1::SessionChunk chunk;
  while (true) {
    std::uint32_t length = 0;
    if (!in.ReadVarint32(&length)) break;
    // A chunk longer than what is left is a truncated stream, refused before parsing as the
    // chunk-file reader does.
    const auto position = static_cast<std::size_t>(in.CurrentPosition());
    if (length > size - position) break;
    // Parsed from its own bytes, as the chunk-file reader parses its buffer: a string field of
    // the chunk claiming more than the chunk holds then fails at once (parsed from the stream,
    // protobuf reserves up to 50 MB for the claim first).
    const bool parsed = chunk.ParseFromArray(data + position, static_cast<int>(length));
    if (!parsed || !in.Skip(static_cast<int>(length))) break;
    try {
      validator.check(chunk);
      const cv::Mat image = validator.take_decoded_image();
      if (chunk.has_depth() || chunk.has_body_index()) {
        const auto& k = validator.header().depth_intrinsics();
        const int type = chunk.has_depth() ? CV_16UC1 : CV_8UC1;
        if (static_cast<std::uint32_t>(image.cols) != k.width() ||
            static_cast<std::uint32_t>(image.rows) != k.height() || image.type() != type) {
          fuzz::invariant_failed("accepted image does not have the header's depth size");
        }
      } else if (!image.empty()) {
        fuzz::invariant_failed("an image handed on for a chunk that is not depth or body index");
      }
    } catch (const Error&) {
      if (!validator.has_header() || chunk.has_header() || chunk.has_end()) break;
    }
  }
  try {
    validator.finish();
  } catch (const Error&) {
  }
  return 0;
}
