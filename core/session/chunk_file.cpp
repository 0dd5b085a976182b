#include "session/chunk_file.hpp"

#include <algorithm>

#include <google/protobuf/io/coded_stream.h>
#include <google/protobuf/io/zero_copy_stream_impl_lite.h>

#include "common/error.hpp"

namespace posefuse::session {

namespace {

constexpr int kMaxVarintBytes = 10;  // a 64-bit varint has at most 10 bytes
constexpr std::uint64_t kReadStepBytes = 1ull << 20;

std::string chunk_field(std::uint64_t index) { return "chunk[" + std::to_string(index) + "]"; }

}  // namespace

ChunkFileReader::ChunkFileReader(const std::filesystem::path& path, std::uint64_t max_chunk_bytes)
    : ChunkFileReader(open_path(path, path.string()), path.string(), max_chunk_bytes) {}

ChunkFileReader::ChunkFileReader(UniqueFd file, const std::string& name, std::uint64_t max_chunk_bytes)
    : max_chunk_bytes_(max_chunk_bytes) {
  require_regular_file(file.get(), name);
  in_ = std::make_unique<FdInputStream>(std::move(file));
}

bool ChunkFileReader::next(SessionChunk& chunk) {
  const std::string field = chunk_field(chunks_read_);
  const std::string where = " (chunk starts at byte offset " + std::to_string(offset_) + ")";

  // Length prefix: base-128 varint, least significant group first.
  std::uint64_t length = 0;
  int bytes = 0;
  while (true) {
    const int c = in_->get();
    if (c == std::char_traits<char>::eof()) {
      if (bytes == 0 && !in_->bad()) return false;  // clean end between chunks
      throw Error(ErrorCode::kDataLoss, field, "file ends inside the length prefix" + where);
    }
    const auto byte = static_cast<std::uint64_t>(c);
    if (bytes == kMaxVarintBytes - 1 && byte > 1) {
      throw Error(ErrorCode::kDataLoss, field, "corrupt length prefix (overflows 64 bits)" + where);
    }
    length |= (byte & 0x7F) << (7 * bytes);
    ++bytes;
    if ((byte & 0x80) == 0) break;
    if (bytes == kMaxVarintBytes) {
      throw Error(ErrorCode::kDataLoss, field, "corrupt length prefix (longer than 10 bytes)" + where);
    }
  }
  if (length > max_chunk_bytes_) {
    throw Error(
        ErrorCode::kResourceExhausted, field,
        "length " + std::to_string(length) + " bytes exceeds the limit of " + std::to_string(max_chunk_bytes_) + where);
  }

  // Read in steps, so that a few bytes claiming a 64 MiB chunk cost what the file holds, not
  // the claimed length (the buffer grows only as the bytes arrive).
  buffer_.clear();
  std::uint64_t got = 0;
  while (got < length) {
    const std::uint64_t step = std::min(length - got, kReadStepBytes);
    buffer_.resize(got + step);
    in_->read(buffer_.data() + got, static_cast<std::streamsize>(step));
    const auto read = static_cast<std::uint64_t>(in_->gcount());
    got += read;
    if (read != step) break;
  }
  if (got != length) {
    throw Error(ErrorCode::kDataLoss, field,
                "truncated: expected " + std::to_string(length) + " bytes, file has " + std::to_string(got) + where);
  }
  chunk.Clear();
  if (!chunk.ParseFromString(buffer_)) {
    throw Error(ErrorCode::kDataLoss, field, "corrupt: not a valid SessionChunk" + where);
  }
  offset_ += static_cast<std::uint64_t>(bytes) + length;
  ++chunks_read_;
  return true;
}

ChunkFileWriter::ChunkFileWriter(const std::filesystem::path& path, std::uint64_t max_chunk_bytes)
    : path_(path), max_chunk_bytes_(max_chunk_bytes) {
  out_.open(path, std::ios::binary | std::ios::trunc);
  if (!out_) throw_precondition(path.string(), "cannot create chunk file");
}

void ChunkFileWriter::write(const SessionChunk& chunk) {
  const std::uint64_t length = chunk.ByteSizeLong();
  if (length > max_chunk_bytes_) {
    throw Error(ErrorCode::kResourceExhausted, chunk_field(chunks_written_),
                "serialised size " + std::to_string(length) + " bytes exceeds the limit of " +
                    std::to_string(max_chunk_bytes_));
  }
  char prefix[kMaxVarintBytes];
  int n = 0;
  std::uint64_t rest = length;
  do {
    const auto group = static_cast<char>(rest & 0x7F);
    rest >>= 7;
    prefix[n++] = static_cast<char>(group | (rest ? 0x80 : 0));
  } while (rest);
  buffer_.clear();
  {
    // Map fields (header options, end counts) would otherwise come out in a per-process random
    // order, and the same session would not give the same bytes twice.
    google::protobuf::io::StringOutputStream stream(&buffer_);
    google::protobuf::io::CodedOutputStream coded(&stream);
    coded.SetSerializationDeterministic(true);
    chunk.SerializeToCodedStream(&coded);
  }
  out_.write(prefix, n);
  out_.write(buffer_.data(), static_cast<std::streamsize>(buffer_.size()));
  if (!out_) throw Error(ErrorCode::kDataLoss, path_.string(), "write failed");
  ++chunks_written_;
}

void ChunkFileWriter::finish() {
  out_.close();
  if (!out_) throw Error(ErrorCode::kDataLoss, path_.string(), "write failed on close");
}

}  // namespace posefuse::session
