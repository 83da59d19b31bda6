#include "io_detail.h"

#include <paco/common/error.h>

#include <cerrno>
#include <cmath>
#include <charconv>
#include <cstdio>
#include <filesystem>
#include <fstream>

// The binary readers and writers move little-endian values with memcpy.
#if defined(__BYTE_ORDER__) && __BYTE_ORDER__ != __ORDER_LITTLE_ENDIAN__
#error "paco::io assumes a little-endian host"
#endif

namespace paco::io::detail {

void fail(const std::string& path, const std::string& problem) {
  throw IoError("'" + path + "': " + problem);
}

void failOnDataAfterDeclared(const std::string& path, std::string_view rest, const std::string& declared) {
  const std::size_t data = rest.find_first_not_of(" \t\r\n");
  if (data == std::string_view::npos) return;
  fail(path, "malformed: the header declares " + declared + ", but " + plural(rest.size() - data, "byte") +
                 " of data follow them; the header undercounts the data: correct its count");
}

std::string readWholeFile(const std::string& path) {
  std::error_code ec;
  const auto status = std::filesystem::status(path, ec);
  if (!std::filesystem::exists(status)) fail(path, "file not found");
  if (std::filesystem::is_directory(status)) fail(path, "is a folder, not a file");
  std::ifstream in(path, std::ios::binary);
  if (!in) fail(path, std::string("cannot open for reading: ") + std::strerror(errno));
  std::string bytes;
  in.seekg(0, std::ios::end);
  const std::streamoff size = in.tellg();
  if (size > 0) {
    bytes.resize(static_cast<std::size_t>(size));
    in.seekg(0, std::ios::beg);
    in.read(bytes.data(), size);
    if (in.gcount() != size) fail(path, "read error: got " + std::to_string(in.gcount()) + " of " +
                                            std::to_string(size) + " bytes");
  }
  if (bytes.empty()) fail(path, "file is empty (0 bytes)");
  return bytes;
}

void writeWholeFile(const std::string& path, const std::string& bytes) {
  std::FILE* file = std::fopen(path.c_str(), "wb");
  if (!file) fail(path, std::string("cannot open for writing: ") + std::strerror(errno));
  const std::size_t written = std::fwrite(bytes.data(), 1, bytes.size(), file);
  const int write_errno = errno;
  const bool closed = std::fclose(file) == 0;
  if (written != bytes.size() || !closed) {
    std::error_code ec;
    std::filesystem::remove(path, ec);  // no partial file
    fail(path, std::string("write failed: ") + std::strerror(closed ? write_errno : errno));
  }
}

// std::to_chars gives the shortest text that reads back to the same value (never more digits
// than %.9g / %.17g), locale-independent and several times faster than snprintf.
void appendFloat(std::string& out, float value) {
  char buffer[32];
  const auto result = std::to_chars(buffer, buffer + sizeof(buffer), value);
  out.append(buffer, result.ptr);
}

void appendDouble(std::string& out, double value) {
  char buffer[40];
  const auto result = std::to_chars(buffer, buffer + sizeof(buffer), value);
  out.append(buffer, result.ptr);
}

Eigen::Vector3d precisionOffset(const Eigen::AlignedBox3d& finite_box) {
  if (finite_box.isEmpty()) return Eigen::Vector3d::Zero();
  const double diagonal = finite_box.diagonal().norm();
  const double largest = finite_box.min().cwiseAbs().cwiseMax(finite_box.max().cwiseAbs()).maxCoeff();
  // float32 rounds to within 2^-24 of the value.
  if (!(diagonal > 0.0) || largest * 0x1p-24 <= 1e-5 * diagonal) return Eigen::Vector3d::Zero();
  const double step = std::pow(10.0, std::ceil(std::log10(diagonal)));
  const Eigen::Vector3d centre = finite_box.center();
  const Eigen::Vector3d tidy = (centre / step).array().round().matrix() * step;
  return tidy.allFinite() ? tidy : centre;
}

double unshift(float value, double offset) {
  if (offset == 0.0 || !std::isfinite(value)) return static_cast<double>(value) + offset;
  char buffer[32];
  const auto printed = std::to_chars(buffer, buffer + sizeof(buffer), value);
  double decimal = value;
  std::from_chars(buffer, printed.ptr, decimal);
  return decimal + offset;
}

void appendCoordinate(std::string& out, float value, double offset) {
  if (offset == 0.0) appendFloat(out, value);
  else appendDouble(out, unshift(value, offset));
}

bool parseDouble(std::string_view token, double& value) {
  if (!token.empty() && token.front() == '+') token.remove_prefix(1);
  if (token.empty()) return false;
  const auto [end, ec] = std::from_chars(token.data(), token.data() + token.size(), value);
  return ec == std::errc() && end == token.data() + token.size();
}

bool parseInt64(std::string_view token, std::int64_t& value) {
  if (!token.empty() && token.front() == '+') token.remove_prefix(1);
  if (token.empty()) return false;
  const auto [end, ec] = std::from_chars(token.data(), token.data() + token.size(), value);
  return ec == std::errc() && end == token.data() + token.size();
}

namespace {
bool isBlank(char c) { return c == ' ' || c == '\t' || c == '\r' || c == '\f' || c == '\v'; }
}  // namespace

void splitTokens(std::string_view line, std::vector<std::string_view>& tokens) {
  tokens.clear();
  std::size_t i = 0;
  while (i < line.size()) {
    while (i < line.size() && isBlank(line[i])) ++i;
    const std::size_t start = i;
    while (i < line.size() && !isBlank(line[i])) ++i;
    if (i > start) tokens.push_back(line.substr(start, i - start));
  }
}

bool splitValues(std::string_view line, std::vector<std::string_view>& values) {
  values.clear();
  bool after_comma = false;  // a comma since the last value, so a value must follow
  std::size_t i = 0;
  while (i < line.size()) {
    if (line[i] == ',') {
      if (after_comma || values.empty()) return false;
      after_comma = true;
      ++i;
    } else if (isBlank(line[i])) {
      ++i;
    } else {
      const std::size_t start = i;
      while (i < line.size() && line[i] != ',' && !isBlank(line[i])) ++i;
      values.push_back(line.substr(start, i - start));
      after_comma = false;
    }
  }
  return !after_comma;
}

std::size_t utf8BomLength(std::string_view text) {
  return text.substr(0, 3) == "\xEF\xBB\xBF" ? 3 : 0;
}

bool TextCursor::nextToken(std::string_view& token) {
  while (pos_ < text_.size() && (isBlank(text_[pos_]) || text_[pos_] == '\n')) {
    if (text_[pos_] == '\n') ++line_;
    ++pos_;
  }
  if (pos_ >= text_.size()) return false;
  const std::size_t start = pos_;
  while (pos_ < text_.size() && !isBlank(text_[pos_]) && text_[pos_] != '\n') ++pos_;
  token = text_.substr(start, pos_ - start);
  return true;
}

bool TextCursor::nextLine(std::string_view& line) {
  if (pos_ >= text_.size()) return false;
  std::size_t end = text_.find('\n', pos_);
  const bool has_newline = end != std::string_view::npos;
  if (!has_newline) end = text_.size();
  std::size_t stop = end;
  if (stop > pos_ && text_[stop - 1] == '\r') --stop;
  line = text_.substr(pos_, stop - pos_);
  pos_ = has_newline ? end + 1 : end;
  if (has_newline) ++line_;
  return true;
}

std::string plural(std::size_t n, const std::string& noun) {
  if (n == 1) return "1 " + noun;
  if (noun == "vertex") return std::to_string(n) + " vertices";
  return std::to_string(n) + " " + noun + "s";
}

std::string numberText(double value) {
  char buffer[40];
  std::snprintf(buffer, sizeof(buffer), "%.9g", value);
  return buffer;
}

}  // namespace paco::io::detail
