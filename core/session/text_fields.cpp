#include "session/text_fields.hpp"

#include <charconv>
#include <cmath>
#include <cstdio>
#include <limits>

#include "common/error.hpp"

namespace posefuse::session {

namespace {

template <typename T>
std::string format_number(T value) {
  if (std::isnan(value)) return "nan";
  char buffer[64];
  const auto result = std::to_chars(buffer, buffer + sizeof buffer, value);
  return std::string(buffer, result.ptr);
}

template <typename T>
T parse_number(std::string_view text, const std::string& field, const char* what) {
  T value{};
  const char* begin = text.data();
  const char* end = text.data() + text.size();
  // from_chars accepts no leading '+'; we never write one and do not accept one.
  const auto result = std::from_chars(begin, end, value);
  if (text.empty() || result.ec != std::errc() || result.ptr != end) {
    throw_invalid(field, quoted(text) + " is not " + what);
  }
  return value;
}

}  // namespace

std::string format_double(double value) { return format_number(value); }
std::string format_float(float value) { return format_number(value); }

double parse_double(std::string_view text, const std::string& field) {
  return parse_number<double>(text, field, "a number");
}

std::string format_seconds(std::int64_t t_us) {
  char text[32];
  const std::int64_t magnitude = t_us < 0 ? -t_us : t_us;
  std::snprintf(text, sizeof text, "%s%lld.%06lld", t_us < 0 ? "-" : "", static_cast<long long>(magnitude / 1000000),
                static_cast<long long>(magnitude % 1000000));
  return text;
}
float parse_float(std::string_view text, const std::string& field) {
  return parse_number<float>(text, field, "a 32-bit float");
}
std::int64_t parse_int64(std::string_view text, const std::string& field) {
  return parse_number<std::int64_t>(text, field, "a 64-bit integer");
}
std::uint64_t parse_uint64(std::string_view text, const std::string& field) {
  return parse_number<std::uint64_t>(text, field, "a non-negative 64-bit integer");
}

std::string quoted(std::string_view text) {
  std::string out;
  out.reserve(text.size() + 2);
  out += '\'';
  out += text;
  out += '\'';
  return out;
}

std::string to_hex(std::string_view bytes) {
  static constexpr char kDigits[] = "0123456789abcdef";
  std::string out;
  out.reserve(bytes.size() * 2);
  for (const char c : bytes) {
    const auto b = static_cast<unsigned char>(c);
    out.push_back(kDigits[b >> 4]);
    out.push_back(kDigits[b & 0xF]);
  }
  return out;
}

std::string from_hex(std::string_view hex, const std::string& field) {
  if (hex.size() % 2 != 0) throw_invalid(field, "hex text has an odd number of digits");
  auto nibble = [&](char c) -> int {
    if (c >= '0' && c <= '9') return c - '0';
    if (c >= 'a' && c <= 'f') return c - 'a' + 10;
    if (c >= 'A' && c <= 'F') return c - 'A' + 10;
    throw_invalid(field, std::string("'") + c + "' is not a hex digit");
  };
  std::string out(hex.size() / 2, '\0');
  for (std::size_t i = 0; i < out.size(); ++i) {
    out[i] = static_cast<char>(nibble(hex[2 * i]) * 16 + nibble(hex[2 * i + 1]));
  }
  return out;
}

CsvReader::CsvReader(const std::filesystem::path& path, std::string name, std::vector<std::string> columns)
    : in_(std::make_unique<std::ifstream>(path)), name_(std::move(name)), columns_(std::move(columns)) {
  if (!*in_) throw Error(ErrorCode::kNotFound, name_, "cannot open " + path.string());
  read_header_row();
}

CsvReader::CsvReader(std::unique_ptr<std::istream> in, std::string name, std::vector<std::string> columns)
    : in_(std::move(in)), name_(std::move(name)), columns_(std::move(columns)) {
  read_header_row();
}

void CsvReader::read_header_row() {
  std::string header;
  std::getline(*in_, header);
  ++line_number_;
  if (!header.empty() && header.back() == '\r') header.pop_back();
  std::string expected;
  for (std::size_t i = 0; i < columns_.size(); ++i) expected += (i ? "," : "") + columns_[i];
  // The row itself is not quoted: a file that is not this CSV at all must not have its first
  // line copied into an error message (and from there into logs and job listings).
  if (header != expected) {
    throw_invalid(name_ + ":1", "header row is not the expected '" + expected + "'");
  }
}

bool CsvReader::next() {
  while (std::getline(*in_, line_)) {
    ++line_number_;
    if (!line_.empty() && line_.back() == '\r') line_.pop_back();
    if (line_.empty()) continue;
    fields_.clear();
    std::string_view rest(line_);
    while (true) {
      const std::size_t comma = rest.find(',');
      fields_.push_back(rest.substr(0, comma));
      if (comma == std::string_view::npos) break;
      rest.remove_prefix(comma + 1);
    }
    if (fields_.size() != columns_.size()) {
      throw_invalid(name_ + ":" + std::to_string(line_number_),
                    "has " + std::to_string(fields_.size()) + " fields, expected " + std::to_string(columns_.size()));
    }
    return true;
  }
  if (in_->bad()) {
    throw Error(ErrorCode::kDataLoss, name_, "read failed after line " + std::to_string(line_number_));
  }
  return false;
}

std::string CsvReader::field(std::size_t column) const {
  return name_ + ":" + std::to_string(line_number_) + ":" + columns_[column];
}

CsvWriter::CsvWriter(const std::filesystem::path& path, const std::vector<std::string>& columns)
    : path_(path), out_(path, std::ios::binary | std::ios::trunc) {
  if (!out_) throw_precondition(path.string(), "cannot create file");
  row(columns);
}

void CsvWriter::row(const std::vector<std::string>& fields) {
  for (std::size_t i = 0; i < fields.size(); ++i) {
    if (i) out_.put(',');
    out_ << fields[i];
  }
  out_.put('\n');
}

void CsvWriter::close() {
  out_.close();
  if (!out_) throw Error(ErrorCode::kDataLoss, path_.string(), "write failed");
}

}  // namespace posefuse::session
