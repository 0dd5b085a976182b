#include "session/convert.hpp"

#include "session/chunk_file.hpp"
#include "session/directory_reader.hpp"
#include "session/directory_writer.hpp"
#include "session/session_validator.hpp"

namespace posefuse::session {

std::uint64_t copy_validated(ChunkSource& source, ChunkSink& sink) {
  SessionValidator validator;
  SessionChunk chunk;
  while (source.next(chunk)) {
    validator.check(chunk);
    sink.write(chunk);
  }
  validator.finish();
  sink.finish();
  return validator.chunks_checked();
}

std::uint64_t directory_to_chunk_file(const std::filesystem::path& directory, const std::filesystem::path& chunk_file) {
  DirectoryReader reader(directory);
  ChunkFileWriter writer(chunk_file);
  return copy_validated(reader, writer);
}

std::uint64_t chunk_file_to_directory(const std::filesystem::path& chunk_file, const std::filesystem::path& directory) {
  ChunkFileReader reader(chunk_file);
  DirectoryWriter writer(directory);
  return copy_validated(reader, writer);
}

}  // namespace posefuse::session
