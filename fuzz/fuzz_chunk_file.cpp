// The chunk file reader (session/chunk_file.*) on arbitrary file bytes: every chunk is read
// until the end or the first error, which must be a posefuse::Error. A file may not make the
// reader allocate much more than its own size (-malloc_limit_mb in scripts/fuzz.sh).
#include <cstddef>
#include <cstdint>

#include "common/error.hpp"
#include "seeds.hpp"
#include "session/chunk_file.hpp"

using namespace posefuse;

extern "C" int LLVMFuzzerInitialize(int*, char***) {
  fuzz::init_harness([] {
    const auto session = fuzz::tiny_session();
    fuzz::Seeds seeds{{"session.pfchunks", fuzz::chunk_file_bytes(session)}};
    seeds.push_back({"header.pfchunks", fuzz::chunk_file_bytes({session.front()})});
    std::string truncated = seeds.front().second;
    truncated.resize(truncated.size() / 2);
    seeds.push_back({"truncated.pfchunks", truncated});
    return seeds;
  });
  return 0;
}

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  try {
    session::ChunkFileReader reader(session::UniqueFd(fuzz::memory_file(data, size)), "fuzz.pfchunks");
    session::SessionChunk chunk;
    std::uint64_t chunks = 0;
    while (reader.next(chunk)) {
      ++chunks;
      if (reader.byte_offset() > size) fuzz::invariant_failed("offset beyond the file");
    }
    if (chunks != reader.chunks_read()) fuzz::invariant_failed("chunk count");
  } catch (const Error&) {
  }
  return 0;
}
