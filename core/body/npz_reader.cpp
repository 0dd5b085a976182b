#include "body/npz_reader.hpp"

#include <zlib.h>

#include <algorithm>
#include <cstring>
#include <fstream>
#include <sstream>

#include "common/error.hpp"

namespace posefuse::body {
namespace {

[[noreturn]] void data_loss(const std::string& field, const std::string& message) {
  throw Error(ErrorCode::kDataLoss, field, message);
}

// Little-endian reads with bounds checks.
class Reader {
 public:
  Reader(std::string_view bytes, std::string field) : bytes_(bytes), field_(std::move(field)) {}
  uint64_t read(size_t offset, int width) const {
    if (offset > bytes_.size() || bytes_.size() - offset < static_cast<size_t>(width))
      data_loss(field_, "truncated: needs " + std::to_string(width) + " bytes at offset " + std::to_string(offset) +
                            ", has " + std::to_string(bytes_.size()));
    uint64_t value = 0;
    for (int i = width - 1; i >= 0; --i) value = (value << 8) | static_cast<unsigned char>(bytes_[offset + i]);
    return value;
  }
  std::string_view slice(uint64_t offset, uint64_t length) const {
    if (offset > bytes_.size() || bytes_.size() - offset < length)
      data_loss(field_, "truncated: member of " + std::to_string(length) + " bytes at offset " +
                            std::to_string(offset) + " runs past the end (" + std::to_string(bytes_.size()) + ")");
    return bytes_.substr(offset, length);
  }
  size_t size() const { return bytes_.size(); }

 private:
  std::string_view bytes_;
  std::string field_;
};

// Value of `key` in the npy header dict, e.g. "'descr': '<f8'" -> "'<f8'".
std::string header_value(const std::string& header, const std::string& key, const std::string& name) {
  const std::string quoted = "'" + key + "'";
  const size_t at = header.find(quoted);
  if (at == std::string::npos) throw_invalid(name + ".header", "no '" + key + "' in " + header);
  size_t start = header.find(':', at + quoted.size());
  if (start == std::string::npos) throw_invalid(name + ".header", "malformed: " + header);
  ++start;
  while (start < header.size() && header[start] == ' ') ++start;
  size_t end = start;
  if (start < header.size() && header[start] == '(') {
    end = header.find(')', start);
    if (end == std::string::npos) throw_invalid(name + ".header", "unterminated shape: " + header);
    ++end;
  } else {
    while (end < header.size() && header[end] != ',' && header[end] != '}') ++end;
  }
  return header.substr(start, end - start);
}

std::vector<int64_t> parse_shape(const std::string& text, const std::string& name) {
  std::vector<int64_t> shape;
  std::string inner = text.substr(1, text.size() - 2);
  std::stringstream stream(inner);
  std::string item;
  while (std::getline(stream, item, ',')) {
    const size_t first = item.find_first_not_of(' ');
    if (first == std::string::npos) continue;
    item = item.substr(first, item.find_last_not_of(' ') - first + 1);
    if (item.empty() || item.find_first_not_of("0123456789") != std::string::npos || item.size() > 12)
      throw_invalid(name + ".shape", "not a shape: " + text);
    shape.push_back(std::stoll(item));
  }
  return shape;
}

template <typename T>
void convert(const char* data, size_t count, std::vector<double>& out) {
  for (size_t i = 0; i < count; ++i) {
    T value;
    std::memcpy(&value, data + i * sizeof(T), sizeof(T));
    out[i] = static_cast<double>(value);
  }
}

// The output grows with what the stream really inflates to: the member's claimed size is not
// allocated up front, so that a small archive claiming gigabytes costs what it holds.
std::string inflate_raw(std::string_view compressed, uint64_t expected_size, const std::string& name) {
  if (expected_size > kMaxNpzMemberBytes)
    throw Error(ErrorCode::kResourceExhausted, name, std::to_string(expected_size) + " bytes exceeds the limit");
  z_stream stream{};
  if (inflateInit2(&stream, -MAX_WBITS) != Z_OK) throw Error(ErrorCode::kInternal, name, "inflateInit2 failed");
  stream.next_in = reinterpret_cast<Bytef*>(const_cast<char*>(compressed.data()));
  stream.avail_in = static_cast<uInt>(compressed.size());
  std::string out;
  char buffer[1 << 16];
  int status = Z_OK;
  while (status == Z_OK && out.size() <= expected_size) {
    stream.next_out = reinterpret_cast<Bytef*>(buffer);
    stream.avail_out = sizeof buffer;
    status = inflate(&stream, Z_NO_FLUSH);
    const std::size_t produced = sizeof buffer - stream.avail_out;
    out.append(buffer, std::min<uint64_t>(produced, expected_size + 1 - out.size()));
    if (status == Z_OK && produced == 0) break;  // input used up before the stream's end
  }
  inflateEnd(&stream);
  if (status != Z_STREAM_END || out.size() != expected_size)
    data_loss(name, "deflate stream is corrupt, truncated or longer than claimed (inflated " +
                        std::to_string(out.size()) + " bytes, " + std::to_string(expected_size) + " claimed)");
  return out;
}

// The number of elements of `shape`, refused above `limit` before the product could overflow.
int64_t element_count(const std::vector<int64_t>& shape, uint64_t limit, const std::string& name) {
  for (const int64_t d : shape) {
    if (d == 0) return 0;
  }
  uint64_t count = 1;
  for (const int64_t d : shape) {
    if (static_cast<uint64_t>(d) > limit / count) {
      throw Error(ErrorCode::kResourceExhausted, name, "array of more than " + std::to_string(limit) + " elements");
    }
    count *= static_cast<uint64_t>(d);
  }
  return static_cast<int64_t>(count);
}

}  // namespace

int64_t NpyArray::size() const {
  int64_t n = 1;
  for (int64_t d : shape) n *= d;
  return n;
}

NpyArray parse_npy(std::string_view bytes, const std::string& name) {
  static const char kMagic[] = "\x93NUMPY";
  if (bytes.size() < 10 || bytes.substr(0, 6) != std::string_view(kMagic, 6))
    data_loss(name, "not an .npy array (bad magic)");
  const Reader reader(bytes, name);
  const int major = static_cast<unsigned char>(bytes[6]);
  size_t header_length = 0, header_start = 0;
  if (major == 1) {
    header_length = reader.read(8, 2);
    header_start = 10;
  } else if (major == 2 || major == 3) {
    header_length = reader.read(8, 4);
    header_start = 12;
  } else {
    throw_invalid(name + ".version", "unsupported .npy version " + std::to_string(major));
  }
  const std::string header(reader.slice(header_start, header_length));
  NpyArray array;
  const std::string descr = header_value(header, "descr", name);
  if (descr.size() < 3 || descr.front() != '\'' || descr.back() != '\'') throw_invalid(name + ".descr", descr);
  array.dtype = descr.substr(1, descr.size() - 2);
  const bool fortran = header_value(header, "fortran_order", name) == "True";
  const std::string shape_text = header_value(header, "shape", name);
  if (shape_text.size() < 2 || shape_text.front() != '(') throw_invalid(name + ".shape", shape_text);
  array.shape = parse_shape(shape_text, name);

  const std::string& t = array.dtype;
  size_t width = 0;
  if (t == "<f8" || t == "<i8" || t == "<u8") width = 8;
  else if (t == "<f4" || t == "<i4" || t == "<u4") width = 4;
  else if (t == "<i2" || t == "<u2") width = 2;
  else if (t == "|u1" || t == "|i1" || t == "|b1") width = 1;
  else throw_invalid(name + ".dtype", "unsupported dtype '" + t + "' (need little-endian int, uint or float)");
  const int64_t count = element_count(array.shape, kMaxNpzMemberBytes / width, name);
  const size_t data_start = header_start + header_length;
  const std::string_view data = reader.slice(data_start, static_cast<uint64_t>(count) * width);
  array.values.resize(static_cast<size_t>(count));
  const size_t n = static_cast<size_t>(count);
  if (t == "<f8") convert<double>(data.data(), n, array.values);
  else if (t == "<f4") convert<float>(data.data(), n, array.values);
  else if (t == "<i8") convert<int64_t>(data.data(), n, array.values);
  else if (t == "<u8") convert<uint64_t>(data.data(), n, array.values);
  else if (t == "<i4") convert<int32_t>(data.data(), n, array.values);
  else if (t == "<u4") convert<uint32_t>(data.data(), n, array.values);
  else if (t == "<i2") convert<int16_t>(data.data(), n, array.values);
  else if (t == "<u2") convert<uint16_t>(data.data(), n, array.values);
  else if (t == "|i1") convert<int8_t>(data.data(), n, array.values);
  else convert<uint8_t>(data.data(), n, array.values);

  if (fortran && array.shape.size() > 1) {  // reorder to C order
    std::vector<double> c_order(array.values.size());
    const size_t dims = array.shape.size();
    std::vector<int64_t> index(dims, 0);
    for (size_t f = 0; f < array.values.size(); ++f) {
      size_t c = 0;
      for (size_t d = 0; d < dims; ++d) c = c * static_cast<size_t>(array.shape[d]) + static_cast<size_t>(index[d]);
      c_order[c] = array.values[f];
      for (size_t d = 0; d < dims; ++d) {  // Fortran order: first index fastest
        if (++index[d] < array.shape[d]) break;
        index[d] = 0;
      }
    }
    array.values = std::move(c_order);
  }
  return array;
}

std::map<std::string, NpyArray> parse_npz(std::string_view bytes, const std::string& name) {
  const Reader reader(bytes, name);
  // End of central directory: 22 bytes plus a comment of up to 65535 bytes.
  if (bytes.size() < 22) data_loss(name, "too short for a zip archive (" + std::to_string(bytes.size()) + " bytes)");
  size_t eocd = std::string_view::npos;
  const size_t lowest = bytes.size() > 22 + 65535 ? bytes.size() - 22 - 65535 : 0;
  for (size_t at = bytes.size() - 22 + 1; at-- > lowest;)
    if (reader.read(at, 4) == 0x06054b50) {
      eocd = at;
      break;
    }
  if (eocd == std::string_view::npos) data_loss(name, "not a zip archive (no end-of-central-directory record)");
  uint64_t entries = reader.read(eocd + 10, 2);
  uint64_t directory = reader.read(eocd + 16, 4);
  if ((entries == 0xFFFF || directory == 0xFFFFFFFF) && eocd >= 20 && reader.read(eocd - 20, 4) == 0x07064b50) {
    const uint64_t record = reader.read(eocd - 20 + 8, 8);  // zip64 end of central directory
    if (reader.read(record, 4) != 0x06064b50) data_loss(name, "bad zip64 end-of-central-directory record");
    entries = reader.read(record + 32, 8);
    directory = reader.read(record + 48, 8);
  }
  std::map<std::string, NpyArray> arrays;
  uint64_t at = directory;
  for (uint64_t e = 0; e < entries; ++e) {
    if (reader.read(at, 4) != 0x02014b50) data_loss(name, "bad central directory entry " + std::to_string(e));
    const uint64_t flags = reader.read(at + 8, 2), method = reader.read(at + 10, 2);
    const uint64_t crc = reader.read(at + 16, 4);
    uint64_t compressed = reader.read(at + 20, 4), uncompressed = reader.read(at + 24, 4);
    const uint64_t name_length = reader.read(at + 28, 2), extra_length = reader.read(at + 30, 2);
    const uint64_t comment_length = reader.read(at + 32, 2);
    uint64_t local = reader.read(at + 42, 4);
    const std::string member(reader.slice(at + 46, name_length));
    // zip64 extended information: only the fields saturated above are present, in this order.
    const std::string_view extra = reader.slice(at + 46 + name_length, extra_length);
    for (size_t x = 0; x + 4 <= extra.size();) {
      const Reader ext(extra, name + "/" + member + ".extra");
      const uint64_t id = ext.read(x, 2), length = ext.read(x + 2, 2);
      if (id == 0x0001) {
        size_t field = x + 4;
        for (uint64_t* value : {&uncompressed, &compressed, &local}) {
          if (*value != 0xFFFFFFFF) continue;
          *value = ext.read(field, 8);
          field += 8;
        }
      }
      x += 4 + length;
    }
    at += 46 + name_length + extra_length + comment_length;
    const std::string field = name + "/" + member;
    if (flags & 1) throw_invalid(field, "encrypted zip members are not supported");
    if (reader.read(local, 4) != 0x04034b50) data_loss(field, "bad local file header");
    const uint64_t data_start = local + 30 + reader.read(local + 26, 2) + reader.read(local + 28, 2);
    const std::string_view stored = reader.slice(data_start, compressed);
    std::string inflated;
    std::string_view content;
    if (method == 0) {
      if (compressed != uncompressed) data_loss(field, "stored member with different sizes");
      content = stored;
    } else if (method == 8) {
      inflated = inflate_raw(stored, uncompressed, field);
      content = inflated;
    } else {
      throw_invalid(field, "unsupported zip compression method " + std::to_string(method));
    }
    const uLong actual_crc =
        crc32(crc32(0L, Z_NULL, 0), reinterpret_cast<const Bytef*>(content.data()), static_cast<uInt>(content.size()));
    if (actual_crc != crc) data_loss(field, "CRC mismatch: archive is corrupt");
    std::string key = member;
    if (key.size() > 4 && key.substr(key.size() - 4) == ".npy") key.resize(key.size() - 4);
    arrays[key] = parse_npy(content, field);
  }
  return arrays;
}

std::map<std::string, NpyArray> read_npz(const std::string& path) {
  std::ifstream file(path, std::ios::binary);
  if (!file) throw Error(ErrorCode::kNotFound, path, "cannot open file");
  std::stringstream buffer;
  buffer << file.rdbuf();
  return parse_npz(buffer.str(), path);
}

}  // namespace posefuse::body
