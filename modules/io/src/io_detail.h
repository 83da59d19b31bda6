#pragma once
// Internal helpers of paco::io: error messages that name the file, whole-file reading with the
// usual checks, bounds-checked byte and text cursors, and exact number formatting.
#include <Eigen/Geometry>

#include <cstddef>
#include <cstdint>
#include <cstring>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

namespace paco::io::detail {

/// Throws paco::IoError "'<path>': <problem>".
[[noreturn]] void fail(const std::string& path, const std::string& problem);

/// Fails when `rest`, the bytes after all the data a header declares (`declared`, e.g. "100
/// points"), holds anything but whitespace: the header undercounts the data, and reading only
/// what it declares would drop the rest without a word.
void failOnDataAfterDeclared(const std::string& path, std::string_view rest, const std::string& declared);

/// The whole file. Fails for a missing file, a folder, an unreadable or an empty file.
std::string readWholeFile(const std::string& path);

/// Writes `bytes` to `path`; fails with the system's reason when it cannot.
void writeWholeFile(const std::string& path, const std::string& bytes);

/// The shortest text that reads back to the same float / double (at most 9 / 17 digits).
void appendFloat(std::string& out, float value);
void appendDouble(std::string& out, double value);

/// The offset a reader subtracts from every position before storing it as float32
/// (LabelledCloud::coordinate_offset). Zero unless float32 would round the coordinates of
/// `finite_box` by more than 1e-5 of its diagonal (coordinates more than ~170 diagonals from 0, as
/// in national grids); then the box centre rounded to a multiple of the power of ten at or above
/// the diagonal, so that the offset reads as a tidy number (85000, 446000). Zero for an empty or
/// single-point box.
Eigen::Vector3d precisionOffset(const Eigen::AlignedBox3d& finite_box);
/// What every reader does with the positions it parsed in double precision: stores
/// `position(i)` (an Eigen::Vector3d) minus precisionOffset of the finite ones into
/// points[i].x/y/z as float32, for every point of `points` (already sized), and returns that
/// offset. Non-finite positions stay non-finite.
template <typename Points, typename Position>
Eigen::Vector3d storePositionsNearZero(Points& points, Position position) {
  Eigen::AlignedBox3d box;
  for (std::size_t i = 0; i < points.size(); ++i) {
    const Eigen::Vector3d x = position(i);
    if (x.allFinite()) box.extend(x);
  }
  const Eigen::Vector3d offset = precisionOffset(box);
  for (std::size_t i = 0; i < points.size(); ++i) points[i].getVector3fMap() = (position(i) - offset).template cast<float>();
  return offset;
}
/// offset + value as a double, where `value` counts as its shortest decimal text ("0.1f" as
/// 0.1), so that a coordinate read as "85123.45" and stored as 123.45f writes back as 85123.45.
/// Exactly `value` when offset is 0.
double unshift(float value, double offset);
/// Appends one coordinate of a point stored relative to `offset` (one component of it) as text:
/// the float's shortest text for a zero offset, else unshift's double.
void appendCoordinate(std::string& out, float value, double offset);

/// Parses a whole token as a number; false when it is not one (trailing garbage included).
bool parseDouble(std::string_view token, double& value);
bool parseInt64(std::string_view token, std::int64_t& value);

/// Splits a line at blanks (space, tab, \r).
void splitTokens(std::string_view line, std::vector<std::string_view>& tokens);

/// Splits a line of values separated by blanks, by commas, or by commas with blanks around them
/// ("1 2 3", "1,2,3", "1, 2, 3"). False when a comma leaves a value empty (",,", or a comma at the
/// start or end of the line), since guessing which value is missing would shift the columns.
bool splitValues(std::string_view line, std::vector<std::string_view>& values);

/// 3 when `text` starts with a UTF-8 byte-order mark (some Windows editors write one), else 0.
/// Text readers start after it.
std::size_t utf8BomLength(std::string_view text);

/// Walks a text buffer token by token or line by line, counting lines for messages.
class TextCursor {
 public:
  TextCursor(std::string_view text, std::size_t offset = 0) : text_(text), pos_(offset) {}
  /// Next blank-separated token (newlines included as blanks); false at the end.
  bool nextToken(std::string_view& token);
  /// Next line without its end-of-line characters; false at the end.
  bool nextLine(std::string_view& line);
  /// 1-based number of the line the cursor is on.
  std::size_t line() const { return line_; }
  std::size_t offset() const { return pos_; }
  bool atEnd() const { return pos_ >= text_.size(); }

 private:
  std::string_view text_;
  std::size_t pos_ = 0;
  std::size_t line_ = 1;
};

/// Little/big-endian scalar reads from a byte buffer; callers check remaining() first.
class ByteCursor {
 public:
  ByteCursor(std::string_view bytes, std::size_t offset = 0) : bytes_(bytes), pos_(offset) {}
  std::size_t remaining() const { return pos_ < bytes_.size() ? bytes_.size() - pos_ : 0; }
  std::size_t offset() const { return pos_; }
  const char* here() const { return bytes_.data() + pos_; }
  void skip(std::size_t n) { pos_ += n; }
  template <typename T>
  T read(bool big_endian = false) {
    T value;
    char raw[sizeof(T)];
    std::memcpy(raw, bytes_.data() + pos_, sizeof(T));
    if (big_endian)
      for (std::size_t i = 0; i < sizeof(T) / 2; ++i) std::swap(raw[i], raw[sizeof(T) - 1 - i]);
    std::memcpy(&value, raw, sizeof(T));
    pos_ += sizeof(T);
    return value;
  }

 private:
  std::string_view bytes_;
  std::size_t pos_ = 0;
};

/// Appends the raw little-endian bytes of a scalar (this code assumes a little-endian host).
template <typename T>
void appendBinary(std::string& out, T value) {
  char raw[sizeof(T)];
  std::memcpy(raw, &value, sizeof(T));
  out.append(raw, sizeof(T));
}

/// "2048 points" / "1 point".
std::string plural(std::size_t n, const std::string& noun);

/// The text of a number for messages: "0.25", "nan".
std::string numberText(double value);

}  // namespace paco::io::detail
