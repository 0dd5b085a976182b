#pragma once
// Minimal reader for NumPy .npy arrays and .npz archives (zip, stored or deflated, with or
// without zip64 fields, as numpy.savez / savez_compressed write them).
//
// Every malformed input raises posefuse::Error naming the archive member or field: kNotFound for
// a missing file, kDataLoss for truncated or corrupt data (bad CRC), kInvalidArgument for an
// unsupported dtype or header, kResourceExhausted beyond the size limit.
#include <cstdint>
#include <map>
#include <string>
#include <string_view>
#include <vector>

namespace posefuse::body {

struct NpyArray {
  std::vector<int64_t> shape;  // C order
  std::vector<double> values;  // converted from the stored dtype, C order
  std::string dtype;           // as stored, e.g. "<f8"
  int64_t size() const;
};

// Parses one .npy file's bytes; `name` is used in error messages.
NpyArray parse_npy(std::string_view bytes, const std::string& name);

// Members of an .npz archive by key (file name without ".npy").
std::map<std::string, NpyArray> parse_npz(std::string_view bytes, const std::string& name);
std::map<std::string, NpyArray> read_npz(const std::string& path);

// Largest archive member we inflate (bytes); SMPL-X with 300 betas is ~0.5 GB.
inline constexpr uint64_t kMaxNpzMemberBytes = uint64_t{1} << 31;

}  // namespace posefuse::body
