#pragma once
// Converters between the two on-disk forms of a recording. Every chunk passes through
// SessionValidator on the way, so a conversion never writes an invalid session: it stops at the
// first bad chunk with that chunk's error (the partial output is left for inspection).
#include <filesystem>

#include "session/chunk_stream.hpp"

namespace posefuse::session {

// Copies `source` to `sink`, validating each chunk, then checks the end marker and finishes the
// sink. Returns the number of chunks copied.
std::uint64_t copy_validated(ChunkSource& source, ChunkSink& sink);

// A recording directory -> a chunk file. Returns the number of chunks written.
std::uint64_t directory_to_chunk_file(const std::filesystem::path& directory, const std::filesystem::path& chunk_file);

// A chunk file -> a new recording directory (which must not exist or be empty).
std::uint64_t chunk_file_to_directory(const std::filesystem::path& chunk_file, const std::filesystem::path& directory);

}  // namespace posefuse::session
