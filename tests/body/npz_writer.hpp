#pragma once
// Test-only writer of .npy/.npz bytes, so that loader tests need no Python or data files.
#include <zlib.h>

#include <cstdint>
#include <cstring>
#include <string>
#include <utility>
#include <vector>

namespace posefuse::body::testing {

inline void put(std::string& out, uint64_t value, int width) {
  for (int i = 0; i < width; ++i) out.push_back(static_cast<char>((value >> (8 * i)) & 0xFF));
}

// .npy version 1.0 with the given dtype ("<f8", "<f4", "<i4", "<u4", "<i8").
inline std::string npy(const std::vector<int64_t>& shape, const std::vector<double>& values,
                       const std::string& dtype = "<f8", bool fortran_order = false) {
  std::string shape_text = "(";
  for (size_t i = 0; i < shape.size(); ++i)
    shape_text += std::to_string(shape[i]) + (shape.size() == 1 || i + 1 < shape.size() ? "," : "");
  shape_text += ")";
  std::string header = "{'descr': '" + dtype + "', 'fortran_order': " + (fortran_order ? "True" : "False") +
                       ", 'shape': " + shape_text + ", }";
  while ((10 + header.size() + 1) % 64 != 0) header.push_back(' ');
  header.push_back('\n');
  std::string out = "\x93NUMPY";
  out.push_back(1);
  out.push_back(0);
  put(out, header.size(), 2);
  out += header;
  std::vector<double> ordered = values;
  if (fortran_order && shape.size() == 2) {
    for (int64_t r = 0; r < shape[0]; ++r)
      for (int64_t c = 0; c < shape[1]; ++c) ordered[c * shape[0] + r] = values[r * shape[1] + c];
  }
  for (double v : ordered) {
    if (dtype == "<f8") {
      char b[8];
      std::memcpy(b, &v, 8);
      out.append(b, 8);
    } else if (dtype == "<f4") {
      float f = static_cast<float>(v);
      char b[4];
      std::memcpy(b, &f, 4);
      out.append(b, 4);
    } else if (dtype == "<i4") put(out, static_cast<uint32_t>(static_cast<int32_t>(v)), 4);
    else if (dtype == "<u4") put(out, static_cast<uint32_t>(v), 4);
    else if (dtype == "<i8") put(out, static_cast<uint64_t>(static_cast<int64_t>(v)), 8);
    else out.append(16, '\0');  // unsupported dtypes: filler bytes
  }
  return out;
}

inline std::string deflate_raw(const std::string& data) {
  z_stream stream{};
  deflateInit2(&stream, 6, Z_DEFLATED, -MAX_WBITS, 8, Z_DEFAULT_STRATEGY);
  std::string out(deflateBound(&stream, static_cast<uLong>(data.size())), '\0');
  stream.next_in = reinterpret_cast<Bytef*>(const_cast<char*>(data.data()));
  stream.avail_in = static_cast<uInt>(data.size());
  stream.next_out = reinterpret_cast<Bytef*>(out.data());
  stream.avail_out = static_cast<uInt>(out.size());
  deflate(&stream, Z_FINISH);
  out.resize(stream.total_out);
  deflateEnd(&stream);
  return out;
}

// Zip archive; `zip64_local` writes sizes in a zip64 extra field of the local headers, as
// numpy.savez does (force_zip64).
inline std::string zip(const std::vector<std::pair<std::string, std::string>>& members, bool deflated,
                       bool zip64_local = false) {
  std::string out, directory;
  for (const auto& [name, content] : members) {
    const std::string data = deflated ? deflate_raw(content) : content;
    const uint32_t crc = static_cast<uint32_t>(
        crc32(crc32(0L, Z_NULL, 0), reinterpret_cast<const Bytef*>(content.data()), static_cast<uInt>(content.size())));
    const uint64_t offset = out.size();
    put(out, 0x04034b50, 4);
    put(out, 45, 2);
    put(out, 0, 2);
    put(out, deflated ? 8 : 0, 2);
    put(out, 0, 4);
    put(out, crc, 4);
    put(out, zip64_local ? 0xFFFFFFFF : data.size(), 4);
    put(out, zip64_local ? 0xFFFFFFFF : content.size(), 4);
    put(out, name.size(), 2);
    put(out, zip64_local ? 20 : 0, 2);
    out += name;
    if (zip64_local) {
      put(out, 1, 2);
      put(out, 16, 2);
      put(out, content.size(), 8);
      put(out, data.size(), 8);
    }
    out += data;
    put(directory, 0x02014b50, 4);
    put(directory, 45, 2);
    put(directory, 45, 2);
    put(directory, 0, 2);
    put(directory, deflated ? 8 : 0, 2);
    put(directory, 0, 4);
    put(directory, crc, 4);
    put(directory, data.size(), 4);
    put(directory, content.size(), 4);
    put(directory, name.size(), 2);
    put(directory, 0, 2);
    put(directory, 0, 2);
    put(directory, 0, 2);
    put(directory, 0, 2);
    put(directory, 0, 4);
    put(directory, offset, 4);
    directory += name;
  }
  const uint64_t directory_offset = out.size();
  out += directory;
  put(out, 0x06054b50, 4);
  put(out, 0, 2);
  put(out, 0, 2);
  put(out, members.size(), 2);
  put(out, members.size(), 2);
  put(out, directory.size(), 4);
  put(out, directory_offset, 4);
  put(out, 0, 2);
  return out;
}

}  // namespace posefuse::body::testing
