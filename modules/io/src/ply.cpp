#include "ply.h"

#include "io_detail.h"

#include <cmath>
#include <limits>

namespace paco::io::detail {

namespace {

bool parseType(const std::string& text, PlyType& type) {
  static const struct {
    const char* name;
    PlyType type;
  } kTypes[] = {{"char", PlyType::Int8},      {"int8", PlyType::Int8},      {"uchar", PlyType::UInt8},
                {"uint8", PlyType::UInt8},    {"short", PlyType::Int16},    {"int16", PlyType::Int16},
                {"ushort", PlyType::UInt16},  {"uint16", PlyType::UInt16},  {"int", PlyType::Int32},
                {"int32", PlyType::Int32},    {"uint", PlyType::UInt32},    {"uint32", PlyType::UInt32},
                {"float", PlyType::Float32},  {"float32", PlyType::Float32}, {"double", PlyType::Float64},
                {"float64", PlyType::Float64}};
  for (const auto& t : kTypes)
    if (text == t.name) {
      type = t.type;
      return true;
    }
  return false;
}

std::size_t typeSize(PlyType type) {
  switch (type) {
    case PlyType::Int8: case PlyType::UInt8: return 1;
    case PlyType::Int16: case PlyType::UInt16: return 2;
    case PlyType::Int32: case PlyType::UInt32: case PlyType::Float32: return 4;
    case PlyType::Float64: return 8;
  }
  return 0;
}

bool isIntegerType(PlyType type) { return type != PlyType::Float32 && type != PlyType::Float64; }

double readBinary(ByteCursor& in, PlyType type, bool big_endian) {
  switch (type) {
    case PlyType::Int8: return in.read<std::int8_t>(big_endian);
    case PlyType::UInt8: return in.read<std::uint8_t>(big_endian);
    case PlyType::Int16: return in.read<std::int16_t>(big_endian);
    case PlyType::UInt16: return in.read<std::uint16_t>(big_endian);
    case PlyType::Int32: return in.read<std::int32_t>(big_endian);
    case PlyType::UInt32: return in.read<std::uint32_t>(big_endian);
    case PlyType::Float32: return in.read<float>(big_endian);
    case PlyType::Float64: return in.read<double>(big_endian);
  }
  return 0;
}

enum class Format { Ascii, BinaryLittle, BinaryBig };

}  // namespace

const char* plyTypeName(PlyType type) {
  switch (type) {
    case PlyType::Int8: return "char";
    case PlyType::UInt8: return "uchar";
    case PlyType::Int16: return "short";
    case PlyType::UInt16: return "ushort";
    case PlyType::Int32: return "int";
    case PlyType::UInt32: return "uint";
    case PlyType::Float32: return "float";
    case PlyType::Float64: return "double";
  }
  return "?";
}

int PlyElement::find(std::initializer_list<const char*> names) const {
  for (const char* wanted : names)
    for (std::size_t p = 0; p < properties.size(); ++p)
      if (properties[p].name == wanted) return static_cast<int>(p);
  return -1;
}

const PlyElement* PlyFile::element(const std::string& name) const {
  for (const auto& e : elements)
    if (e.name == name) return &e;
  return nullptr;
}

PlyFile readPly(const std::string& path, const std::string& bytes) {
  const std::size_t start = utf8BomLength(bytes);
  if (bytes.size() < start + 4 || bytes.compare(start, 3, "ply") != 0 ||
      (bytes[start + 3] != '\n' && bytes[start + 3] != '\r'))
    fail(path, "malformed: not a PLY file (it does not start with the line \"ply\")");
  const std::size_t header_end = bytes.find("end_header");
  if (header_end == std::string::npos) fail(path, "malformed: PLY header has no end_header line");
  std::size_t data_start = bytes.find('\n', header_end);
  if (data_start == std::string::npos) data_start = bytes.size(); else ++data_start;

  PlyFile ply;
  Format format = Format::Ascii;
  bool have_format = false;
  TextCursor header(std::string_view(bytes).substr(0, header_end), start);
  std::string_view line;
  std::vector<std::string_view> tok;
  header.nextLine(line);  // "ply"
  while (header.nextLine(line)) {
    const std::size_t line_number = header.line() - 1;
    splitTokens(line, tok);
    if (tok.empty() || tok[0] == "comment" || tok[0] == "obj_info") continue;
    const auto bad = [&](const std::string& why) {
      fail(path, "malformed PLY header, line " + std::to_string(line_number) + ": " + why);
    };
    if (tok[0] == "format") {
      if (tok.size() < 2) bad("format without a value");
      if (tok[1] == "ascii") format = Format::Ascii;
      else if (tok[1] == "binary_little_endian") format = Format::BinaryLittle;
      else if (tok[1] == "binary_big_endian") format = Format::BinaryBig;
      else bad("unknown format '" + std::string(tok[1]) + "'");
      have_format = true;
    } else if (tok[0] == "element") {
      std::int64_t count = 0;
      if (tok.size() != 3 || !parseInt64(tok[2], count) || count < 0)
        bad("expected \"element <name> <count>\"");
      PlyElement e;
      e.name = std::string(tok[1]);
      e.count = static_cast<std::size_t>(count);
      ply.elements.push_back(std::move(e));
    } else if (tok[0] == "property") {
      if (ply.elements.empty()) bad("property before any element");
      PlyProperty p;
      if (tok.size() == 3) {
        if (!parseType(std::string(tok[1]), p.type)) bad("unknown type '" + std::string(tok[1]) + "'");
        p.name = std::string(tok[2]);
      } else if (tok.size() == 5 && tok[1] == "list") {
        p.is_list = true;
        if (!parseType(std::string(tok[2]), p.count_type) || !isIntegerType(p.count_type))
          bad("bad list count type '" + std::string(tok[2]) + "'");
        if (!parseType(std::string(tok[3]), p.type)) bad("unknown type '" + std::string(tok[3]) + "'");
        p.name = std::string(tok[4]);
      } else {
        bad("expected \"property <type> <name>\" or \"property list <count type> <type> <name>\"");
      }
      ply.elements.back().properties.push_back(p);
    } else {
      bad("unknown keyword '" + std::string(tok[0]) + "'");
    }
  }
  if (!have_format) fail(path, "malformed PLY header: no format line");

  const bool big_endian = format == Format::BinaryBig;
  ByteCursor bin(bytes, data_start);
  TextCursor text(bytes, data_start);
  std::string_view token;
  for (auto& e : ply.elements) {
    const std::size_t np = e.properties.size();
    e.scalars.assign(np, {});
    e.list_items.assign(np, {});
    e.list_offsets.assign(np, {});
    // Bound the allocation by what the file can hold (at least one byte per value).
    const std::size_t available = bytes.size() - std::min(bytes.size(), data_start);
    const std::size_t reserve = std::min(e.count, available);
    for (std::size_t p = 0; p < np; ++p) {
      if (e.properties[p].is_list) {
        e.list_offsets[p].reserve(reserve + 1);
        e.list_offsets[p].push_back(0);
      } else {
        e.scalars[p].reserve(reserve);
      }
    }
    const auto truncated = [&](std::size_t record) {
      fail(path, "truncated: header says " + plural(e.count, e.name) + ", data holds " + std::to_string(record));
    };
    const auto readValue = [&](std::size_t record, PlyType type, double& value) {
      if (format == Format::Ascii) {
        if (!text.nextToken(token)) truncated(record);
        if (!parseDouble(token, value) && text.atEnd())
          fail(path, "truncated: header says " + plural(e.count, e.name) + ", data ends inside " + e.name + " " +
                         std::to_string(record));
        if (!parseDouble(token, value))
          fail(path, "malformed: '" + std::string(token) + "' is not a number (" + e.name + " " +
                         std::to_string(record) + ", line " + std::to_string(text.line()) + ")");
        if (isIntegerType(type) && (std::floor(value) != value))
          fail(path, "malformed: '" + std::string(token) + "' is not an integer (" + e.name + " " +
                         std::to_string(record) + ", line " + std::to_string(text.line()) + ")");
      } else {
        if (bin.remaining() < typeSize(type)) truncated(record);
        value = readBinary(bin, type, big_endian);
      }
    };
    for (std::size_t r = 0; r < e.count && np > 0; ++r) {
      for (std::size_t p = 0; p < np; ++p) {
        const PlyProperty& prop = e.properties[p];
        double value = 0;
        if (!prop.is_list) {
          readValue(r, prop.type, value);
          e.scalars[p].push_back(value);
          continue;
        }
        readValue(r, prop.count_type, value);
        if (value < 0 || value > static_cast<double>(std::numeric_limits<std::uint32_t>::max()))
          fail(path, "malformed: " + e.name + " " + std::to_string(r) + " has a list of " + numberText(value) +
                         " items");
        const auto n = static_cast<std::size_t>(value);
        // A list longer than the rest of the file: the file was cut short, or the count is corrupt
        // (0xFFFFFFFF in a file of a few kilobytes); say both numbers so the user can tell which.
        if (format != Format::Ascii && bin.remaining() < n * typeSize(prop.type))
          fail(path, "truncated: header says " + plural(e.count, e.name) + "; " + e.name + " " + std::to_string(r) +
                         " has a list of " + plural(n, "item") + " (" + plural(n * typeSize(prop.type), "byte") +
                         ") but the file ends " + plural(bin.remaining(), "byte") +
                         " later; if the file is whole, that list count is corrupt");
        auto& items = e.list_items[p];
        for (std::size_t i = 0; i < n; ++i) {
          readValue(r, prop.type, value);
          items.push_back(value);
        }
        e.list_offsets[p].push_back(items.size());
      }
    }
  }
  std::string declared;
  for (const auto& e : ply.elements) declared += (declared.empty() ? "" : " and ") + plural(e.count, e.name);
  failOnDataAfterDeclared(path,
                          std::string_view(bytes).substr(format == Format::Ascii ? text.offset()
                                                                                 : bytes.size() - bin.remaining()),
                          declared.empty() ? "no element" : declared);
  return ply;
}

}  // namespace paco::io::detail
