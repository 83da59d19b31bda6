// NumPy .npy v1/v2/v3 reader and writer. The header is a Python dict literal; it is parsed as such
// (not searched for substrings) so that key order and spacing do not matter.
#include <paco/io/npy_io.h>

#include "io_detail.h"

#include <paco/common/error.h>

#include <cctype>
#include <limits>
#include <map>

namespace paco::io {

namespace {

using detail::fail;

/// A value of the header dict: a string, a boolean or a tuple of integers.
struct DictValue {
  enum Kind { String, Bool, Tuple } kind = String;
  std::string text;
  bool flag = false;
  std::vector<std::size_t> tuple;
};

class DictParser {
 public:
  DictParser(const std::string& path, std::string_view text) : path_(path), s_(text) {}

  std::map<std::string, DictValue> parse() {
    std::map<std::string, DictValue> dict;
    expect('{');
    while (true) {
      skipSpace();
      if (peek() == '}') break;
      const std::string key = parseString();
      expect(':');
      dict[key] = parseValue();
      skipSpace();
      if (peek() == ',') {
        ++i_;
        continue;
      }
      if (peek() != '}') bad("expected ',' or '}'");
    }
    return dict;
  }

 private:
  [[noreturn]] void bad(const std::string& why) {
    fail(path_, "malformed .npy header (" + why + " at character " + std::to_string(i_) + "): " + std::string(s_));
  }
  void skipSpace() {
    while (i_ < s_.size() && std::isspace(static_cast<unsigned char>(s_[i_]))) ++i_;
  }
  char peek() { return i_ < s_.size() ? s_[i_] : '\0'; }
  void expect(char c) {
    skipSpace();
    if (peek() != c) bad(std::string("expected '") + c + "'");
    ++i_;
  }
  std::string parseString() {
    skipSpace();
    const char quote = peek();
    if (quote != '\'' && quote != '"') bad("expected a quoted string");
    const std::size_t end = s_.find(quote, i_ + 1);
    if (end == std::string_view::npos) bad("unterminated string");
    std::string text(s_.substr(i_ + 1, end - i_ - 1));
    i_ = end + 1;
    return text;
  }
  std::size_t parseInteger() {
    skipSpace();
    std::size_t start = i_;
    while (i_ < s_.size() && std::isdigit(static_cast<unsigned char>(s_[i_]))) ++i_;
    // Python 2 wrote long integers as "7L".
    std::int64_t value = 0;
    if (!detail::parseInt64(s_.substr(start, i_ - start), value) || value < 0) bad("expected a dimension");
    if (peek() == 'L') ++i_;
    return static_cast<std::size_t>(value);
  }
  DictValue parseValue() {
    skipSpace();
    DictValue v;
    if (peek() == '\'' || peek() == '"') {
      v.kind = DictValue::String;
      v.text = parseString();
    } else if (s_.substr(i_, 4) == "True") {
      v.kind = DictValue::Bool;
      v.flag = true;
      i_ += 4;
    } else if (s_.substr(i_, 5) == "False") {
      v.kind = DictValue::Bool;
      i_ += 5;
    } else if (peek() == '(') {
      v.kind = DictValue::Tuple;
      ++i_;
      while (true) {
        skipSpace();
        if (peek() == ')') {
          ++i_;
          break;
        }
        v.tuple.push_back(parseInteger());
        skipSpace();
        if (peek() == ',') ++i_;
        else if (peek() != ')') bad("expected ',' or ')' in the shape");
      }
    } else {
      bad("unsupported value");
    }
    return v;
  }

  const std::string& path_;
  std::string_view s_;
  std::size_t i_ = 0;
};

const char kMagic[] = "\x93NUMPY";

}  // namespace

NpyArray loadNpy(const std::string& path) {
  const std::string bytes = detail::readWholeFile(path);
  if (bytes.size() < 10 || bytes.compare(0, 6, kMagic, 6) != 0) {
    if (bytes.size() < 10 && std::string(kMagic, 6).compare(0, bytes.size(), bytes) == 0)
      fail(path, "truncated: the .npy header is cut off after " + detail::plural(bytes.size(), "byte"));
    fail(path, "malformed: not a .npy file (no \\x93NUMPY magic)");
  }
  const auto major = static_cast<unsigned char>(bytes[6]);
  detail::ByteCursor in(bytes, 8);
  std::size_t header_len = 0;
  if (major == 1) {
    header_len = in.read<std::uint16_t>();
  } else if (major == 2 || major == 3) {
    if (in.remaining() < 4) fail(path, "truncated: the .npy header is cut off");
    header_len = in.read<std::uint32_t>();
  } else {
    fail(path, "unsupported .npy format version " + std::to_string(major) + "; this reader knows 1, 2 and 3");
  }
  if (in.remaining() < header_len)
    fail(path, "truncated: the .npy header says " + detail::plural(header_len, "byte") + ", file holds " +
                   std::to_string(in.remaining()));
  const std::string_view header(bytes.data() + in.offset(), header_len);
  in.skip(header_len);
  const auto dict = DictParser(path, header).parse();

  const auto get = [&](const char* key, DictValue::Kind kind) -> const DictValue& {
    const auto it = dict.find(key);
    if (it == dict.end()) fail(path, std::string("malformed .npy header: no '") + key + "' entry");
    if (it->second.kind != kind) fail(path, std::string("malformed .npy header: bad '") + key + "' entry");
    return it->second;
  };
  const std::string descr = get("descr", DictValue::String).text;
  const bool fortran = get("fortran_order", DictValue::Bool).flag;
  const std::vector<std::size_t> shape = get("shape", DictValue::Tuple).tuple;

  bool big_endian = false;
  std::size_t item = 0;
  if (descr.size() == 3 && (descr[0] == '<' || descr[0] == '>' || descr[0] == '=' || descr[0] == '|') &&
      descr[1] == 'f' && (descr[2] == '4' || descr[2] == '8')) {
    big_endian = descr[0] == '>';
    item = descr[2] == '4' ? 4 : 8;
  } else {
    fail(path, "unsupported .npy dtype '" + descr + "'; expected float32 ('<f4') or float64 ('<f8')");
  }
  NpyArray a;
  if (shape.size() == 1) {
    a.rows = shape[0];
    a.cols = 1;
  } else if (shape.size() == 2) {
    a.rows = shape[0];
    a.cols = shape[1];
  } else {
    fail(path, "unsupported .npy shape with " + std::to_string(shape.size()) + " dimensions; expected 1 or 2");
  }
  const std::size_t max_values = std::numeric_limits<std::size_t>::max() / 16;
  if (a.cols != 0 && a.rows > max_values / a.cols) fail(path, "malformed: .npy shape is too large");
  const std::size_t count = a.rows * a.cols;
  if (in.remaining() / item < count)
    fail(path, "truncated: header says shape (" + std::to_string(a.rows) + ", " + std::to_string(a.cols) +
                   "), i.e. " + std::to_string(count) + " values, data holds " + std::to_string(in.remaining() / item));
  a.data.resize(count);
  for (std::size_t k = 0; k < count; ++k) {
    const double v = item == 4 ? static_cast<double>(in.read<float>(big_endian)) : in.read<double>(big_endian);
    // Fortran order stores columns one after another.
    const std::size_t index = fortran && a.rows > 0 ? (k % a.rows) * a.cols + k / a.rows : k;
    a.data[index] = v;
  }
  if (in.remaining() > 0)
    fail(path, "malformed: header says shape (" + std::to_string(a.rows) + ", " + std::to_string(a.cols) + "), but " +
                   detail::plural(in.remaining(), "byte") + " of data follow those " + std::to_string(count) +
                   " values; the header undercounts the data: correct its shape");
  return a;
}

void saveNpy(const std::string& path, const NpyArray& array, bool float64) {
  if (array.data.size() != array.rows * array.cols)
    throw IoError("saveNpy('" + path + "'): " + std::to_string(array.data.size()) + " values for shape (" +
                  std::to_string(array.rows) + ", " + std::to_string(array.cols) + ")");
  std::string dict = std::string("{'descr': '") + (float64 ? "<f8" : "<f4") + "', 'fortran_order': False, 'shape': (" +
                     std::to_string(array.rows) + ", " + std::to_string(array.cols) + "), }";
  // Pad with spaces so that the data starts at a multiple of 64 bytes, as NumPy does.
  const std::size_t unpadded = 10 + dict.size() + 1;
  dict.append((64 - unpadded % 64) % 64, ' ');
  dict += '\n';
  std::string out(kMagic, 6);
  out += '\x01';
  out += '\x00';
  detail::appendBinary(out, static_cast<std::uint16_t>(dict.size()));
  out += dict;
  out.reserve(out.size() + array.data.size() * (float64 ? 8 : 4));
  for (double v : array.data) {
    if (float64) detail::appendBinary(out, v);
    else detail::appendBinary(out, static_cast<float>(v));
  }
  detail::writeWholeFile(path, out);
}

}  // namespace paco::io
