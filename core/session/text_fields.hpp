#pragma once
// Number <-> text for the directory form's CSV files, and a streaming CSV reader.
//
// Numbers are written with std::to_chars' shortest form, which reads back to the identical
// binary value, so a chunk file -> directory -> chunk file round trip is exact. Fields never
// contain commas or quotes (device ids are restricted, payloads are hex), so no quoting.
#include <cstdint>
#include <filesystem>
#include <fstream>
#include <istream>
#include <memory>
#include <string>
#include <string_view>
#include <vector>

namespace posefuse::session {

std::string format_double(double value);
std::string format_float(float value);
// Seconds with exactly the microseconds of t_us ("12.033333").
std::string format_seconds(std::int64_t t_us);

// Parse one whole field; throw posefuse::Error (kInvalidArgument) naming `field` otherwise.
// "nan", "inf" and "-inf" parse (the validators decide whether they are allowed).
double parse_double(std::string_view text, const std::string& field);
float parse_float(std::string_view text, const std::string& field);
std::int64_t parse_int64(std::string_view text, const std::string& field);
std::uint64_t parse_uint64(std::string_view text, const std::string& field);

std::string to_hex(std::string_view bytes);
// 'text' in single quotes, for error messages.
std::string quoted(std::string_view text);
std::string from_hex(std::string_view hex, const std::string& field);

// Reads a CSV file line by line, checking the header row against `columns`.
// Field names in errors read "<name>:<line>:<column>", e.g. "imu/left.csv:12:gx".
class CsvReader {
 public:
  // `name` is the path shown in errors (relative to the recording directory).
  CsvReader(const std::filesystem::path& path, std::string name, std::vector<std::string> columns);
  // Reads an already open stream (a recording's file opened beneath its directory).
  CsvReader(std::unique_ptr<std::istream> in, std::string name, std::vector<std::string> columns);

  // Next data row (empty lines are skipped); false at end of file.
  bool next();
  std::string_view at(std::size_t column) const { return fields_[column]; }
  // The error field name of `column` in the current row.
  std::string field(std::size_t column) const;
  std::size_t line_number() const { return line_number_; }

 private:
  void read_header_row();

  std::unique_ptr<std::istream> in_;
  std::string name_;
  std::vector<std::string> columns_;
  std::string line_;
  std::vector<std::string_view> fields_;
  std::size_t line_number_ = 0;
};

// Writes rows; the header row is written on construction.
class CsvWriter {
 public:
  CsvWriter(const std::filesystem::path& path, const std::vector<std::string>& columns);
  void row(const std::vector<std::string>& fields);
  void close();  // flushes; throws kDataLoss when the write failed

 private:
  std::filesystem::path path_;
  std::ofstream out_;
};

}  // namespace posefuse::session
