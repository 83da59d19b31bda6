// PCD reader and writer (ascii, binary, binary_compressed) written against the PCD v0.7 spec, so
// that every size is checked before it is used (PCL's reader trusts the header).
#include "cloud_formats.h"
#include "io_detail.h"
#include "lzf.h"

#include <paco/common/error.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <limits>

namespace paco::io::detail {

namespace {

struct PcdField {
  std::string name;
  std::size_t size = 4;
  char type = 'F';
  std::size_t count = 1;
  std::size_t offset = 0;  ///< byte offset in a binary record
};

double readScalar(const char* data, const PcdField& f) {
  ByteCursor in(std::string_view(data, f.size));
  switch (f.type) {
    case 'F':
      return f.size == 8 ? in.read<double>() : static_cast<double>(in.read<float>());
    case 'I':
      switch (f.size) {
        case 1: return in.read<std::int8_t>();
        case 2: return in.read<std::int16_t>();
        case 4: return in.read<std::int32_t>();
        default: return static_cast<double>(in.read<std::int64_t>());
      }
    default:
      switch (f.size) {
        case 1: return in.read<std::uint8_t>();
        case 2: return in.read<std::uint16_t>();
        case 4: return in.read<std::uint32_t>();
        default: return static_cast<double>(in.read<std::uint64_t>());
      }
  }
}

int findField(const std::vector<PcdField>& fields, std::initializer_list<const char*> names) {
  for (const char* n : names)
    for (std::size_t i = 0; i < fields.size(); ++i)
      if (fields[i].name == n) return static_cast<int>(i);
  return -1;
}

}  // namespace

int labelFromValue(const std::string& path, double value, std::size_t point) {
  // Unsigned 32-bit labels of -1 (PCL's PointXYZL) come back as 4294967295.
  if (value == 4294967295.0) return -1;
  if (!std::isfinite(value) || std::floor(value) != value || value < std::numeric_limits<int>::min() ||
      value > std::numeric_limits<int>::max())
    fail(path, "malformed: label " + numberText(value) + " of point " + std::to_string(point) +
                   " is not an integer");
  return static_cast<int>(value);
}

LabelledCloud readPcd(const std::string& path, const std::string& bytes) {
  std::vector<PcdField> fields;
  std::size_t width = 0, height = 1, points = 0;
  bool have_points = false, have_width = false;
  std::string data_kind;
  std::vector<std::string_view> tok;
  TextCursor cursor(bytes, utf8BomLength(bytes));
  std::string_view line;
  std::size_t data_offset = 0;
  while (data_kind.empty()) {
    const std::size_t line_number = cursor.line();
    if (!cursor.nextLine(line)) fail(path, "malformed PCD header: no DATA line");
    splitTokens(line, tok);
    if (tok.empty() || tok[0].front() == '#') continue;
    const auto bad = [&](const std::string& why) {
      fail(path, "malformed PCD header, line " + std::to_string(line_number) + ": " + why);
    };
    const auto count = [&](std::size_t& value) {
      std::int64_t v = 0;
      if (tok.size() != 2 || !parseInt64(tok[1], v) || v < 0)
        bad("expected \"" + std::string(tok[0]) + " <non-negative integer>\"");
      value = static_cast<std::size_t>(v);
    };
    const std::string key(tok[0]);
    if (key == "VERSION" || key == "VIEWPOINT") {
      continue;
    } else if (key == "FIELDS" || key == "COLUMNS") {
      fields.clear();
      for (std::size_t i = 1; i < tok.size(); ++i) fields.push_back({std::string(tok[i])});
    } else if (key == "SIZE" || key == "TYPE" || key == "COUNT") {
      if (tok.size() != fields.size() + 1)
        bad(key + " has " + std::to_string(tok.size() - 1) + " entries for " + plural(fields.size(), "field"));
      for (std::size_t i = 0; i < fields.size(); ++i) {
        std::int64_t v = 0;
        if (key == "TYPE") {
          if (tok[i + 1] != "F" && tok[i + 1] != "I" && tok[i + 1] != "U")
            bad("TYPE '" + std::string(tok[i + 1]) + "' is not F, I or U");
          fields[i].type = tok[i + 1][0];
        } else if (!parseInt64(tok[i + 1], v) || v < 1 || (key == "SIZE" && v != 1 && v != 2 && v != 4 && v != 8) ||
                   (key == "COUNT" && v > 1000000)) {
          bad(key + " entry '" + std::string(tok[i + 1]) + "' is invalid");
        } else if (key == "SIZE") {
          fields[i].size = static_cast<std::size_t>(v);
        } else {
          fields[i].count = static_cast<std::size_t>(v);
        }
      }
    } else if (key == "WIDTH") {
      count(width);
      have_width = true;
    } else if (key == "HEIGHT") {
      count(height);
    } else if (key == "POINTS") {
      count(points);
      have_points = true;
    } else if (key == "DATA") {
      if (tok.size() != 2 || (tok[1] != "ascii" && tok[1] != "binary" && tok[1] != "binary_compressed"))
        bad("DATA must be ascii, binary or binary_compressed");
      data_kind = std::string(tok[1]);
      data_offset = cursor.offset();
    } else {
      bad("unknown keyword '" + key + "'" + (line_number == 1 ? " (is this a PCD file?)" : ""));
    }
  }
  if (fields.empty()) fail(path, "malformed PCD header: no FIELDS line");
  if (height != 0 && width > std::numeric_limits<std::uint32_t>::max() / height)
    fail(path, "malformed PCD header: WIDTH x HEIGHT is too large");
  if (!have_points) points = width * height;
  if (have_width && width * height != points)
    fail(path, "malformed PCD header: WIDTH x HEIGHT = " + std::to_string(width * height) + " but POINTS " +
                   std::to_string(points));
  for (const auto& f : fields)
    if (f.type == 'F' && f.size != 4 && f.size != 8)
      fail(path, "malformed PCD header: float field '" + f.name + "' has size " + std::to_string(f.size));
  std::size_t stride = 0;
  for (auto& f : fields) {
    f.offset = stride;
    stride += f.size * f.count;
  }
  const int ix = findField(fields, {"x"}), iy = findField(fields, {"y"}), iz = findField(fields, {"z"});
  if (ix < 0 || iy < 0 || iz < 0) fail(path, "malformed: PCD file has no x, y, z fields");
  const int inx = findField(fields, {"normal_x"}), iny = findField(fields, {"normal_y"}),
            inz = findField(fields, {"normal_z"});
  const bool has_normals = inx >= 0 && iny >= 0 && inz >= 0;
  const int ilabel = findField(fields, {"label"});

  // Every point as a row of doubles, one per field (first element of multi-count fields).
  const std::size_t available = bytes.size() - data_offset;
  std::vector<double> values;
  if (data_kind == "ascii") {
    values.resize(std::min(points, available / 2) * fields.size());
    TextCursor text(bytes, data_offset);
    std::string_view token;
    for (std::size_t p = 0; p < points; ++p)
      for (std::size_t f = 0; f < fields.size(); ++f)
        for (std::size_t c = 0; c < fields[f].count; ++c) {
          if (!text.nextToken(token))
            fail(path, "truncated: header says " + plural(points, "point") + ", data holds " +
                           std::to_string(p));
          double v = 0;
          if (!parseDouble(token, v) && text.atEnd())
            fail(path, "truncated: header says " + plural(points, "point") + ", data ends inside point " +
                           std::to_string(p));
          if (!parseDouble(token, v))
            fail(path, "malformed: '" + std::string(token) + "' is not a number (point " + std::to_string(p) +
                           ", line " + std::to_string(text.line()) + ")");
          if (c != 0) continue;
          if (values.size() <= p * fields.size() + f) values.resize(2 * values.size() + fields.size());
          values[p * fields.size() + f] = v;
        }
    failOnDataAfterDeclared(path, std::string_view(bytes).substr(text.offset()), plural(points, "point"));
  } else if (data_kind == "binary") {
    if (stride == 0 || available / stride < points)
      fail(path, "truncated: header says " + plural(points, "point") + ", data holds " +
                     std::to_string(stride ? available / stride : 0));
    // Binary data has no separators: whatever follows the declared points, even a newline, is
    // more data once it fills a point.
    if (available - points * stride >= stride)
      fail(path, "malformed: the header declares " + plural(points, "point") + ", but the data holds " +
                     std::to_string(available / stride) + "; the header undercounts the data: correct POINTS and WIDTH");
    values.resize(points * fields.size());
    for (std::size_t p = 0; p < points; ++p)
      for (std::size_t f = 0; f < fields.size(); ++f)
        values[p * fields.size() + f] = readScalar(bytes.data() + data_offset + p * stride + fields[f].offset, fields[f]);
  } else {
    ByteCursor in(bytes, data_offset);
    if (in.remaining() < 8) fail(path, "truncated: binary_compressed data has no size words");
    const auto compressed = in.read<std::uint32_t>();
    const auto uncompressed = in.read<std::uint32_t>();
    if (stride == 0 || points > std::numeric_limits<std::uint32_t>::max() / stride ||
        uncompressed != points * stride)
      fail(path, "malformed: compressed block holds " + std::to_string(uncompressed) + " bytes, header says " +
                     plural(points, "point") + " of " + std::to_string(stride) + " bytes");
    if (in.remaining() < compressed)
      fail(path, "truncated: header says " + plural(points, "point") + ", data holds " +
                     std::to_string(in.remaining()) + " of " + std::to_string(compressed) + " compressed bytes");
    // LZF never shrinks data by more than a factor of ~130; a larger claim is a corrupt header.
    if (uncompressed / 200 > compressed)
      fail(path, "malformed: compressed block claims " + std::to_string(uncompressed) + " bytes from " +
                     std::to_string(compressed) + " compressed bytes");
    std::string raw;
    values.resize(points * fields.size());
    if (uncompressed > 0 && !lzfDecompress(std::string_view(in.here(), compressed), uncompressed, raw))
      fail(path, "malformed: compressed data is corrupt (it does not expand to " + std::to_string(uncompressed) +
                     " bytes)");
    // Compressed PCD stores each field for all points in turn (structure of arrays).
    std::size_t field_start = 0;
    for (std::size_t f = 0; f < fields.size(); ++f) {
      const std::size_t item = fields[f].size * fields[f].count;
      for (std::size_t p = 0; p < points; ++p)
        values[p * fields.size() + f] = readScalar(raw.data() + field_start + p * item, fields[f]);
      field_start += item * points;
    }
  }

  LabelledCloud cloud;
  cloud.has_normals = has_normals;
  cloud.points.resize(points);
  if (ilabel >= 0) cloud.labels.resize(points);
  const std::size_t nf = fields.size();
  cloud.coordinate_offset = storePositionsNearZero(cloud.points, [&](std::size_t p) {
    const double* row = values.data() + p * nf;
    return Eigen::Vector3d(row[ix], row[iy], row[iz]);
  });
  for (std::size_t p = 0; p < points; ++p) {
    const double* row = values.data() + p * nf;
    pcl::PointNormal& q = cloud.points[p];
    q.normal_x = has_normals ? static_cast<float>(row[inx]) : 0.0f;
    q.normal_y = has_normals ? static_cast<float>(row[iny]) : 0.0f;
    q.normal_z = has_normals ? static_cast<float>(row[inz]) : 0.0f;
    q.curvature = 0.0f;
    if (ilabel >= 0) {
      double label = row[ilabel];
      // "U 4" labels hold negative ones in two's complement.
      if (fields[static_cast<std::size_t>(ilabel)].type == 'U' && fields[static_cast<std::size_t>(ilabel)].size == 4 &&
          label > std::numeric_limits<int>::max())
        label -= 4294967296.0;
      cloud.labels[p] = labelFromValue(path, label, p);
    }
  }
  cloud.points.width = static_cast<std::uint32_t>(points);
  cloud.points.height = 1;
  return cloud;
}

std::string writePcd(const LabelledCloud& cloud, PcdEncoding encoding) {
  const std::size_t n = cloud.points.size();
  const bool labels = cloud.hasLabels();
  const bool colours = cloud.hasColours();
  std::string out = "# .PCD v0.7 - Point Cloud Data file format (written by paco)\nVERSION 0.7\nFIELDS x y z";
  if (cloud.has_normals) out += " normal_x normal_y normal_z";
  if (colours) out += " rgb";
  if (labels) out += " label";
  const std::size_t nfloat = cloud.has_normals ? 6 : 3;
  const std::size_t nf = nfloat + (colours ? 1 : 0) + (labels ? 1 : 0);
  out += "\nSIZE";
  for (std::size_t i = 0; i < nf; ++i) out += " 4";
  out += "\nTYPE";
  // Colours are "rgb F 4" holding the packed 0xRRGGBB bits, as PCL's PointXYZRGB writes them.
  // Labels are "U 4" like PCL's PointXYZL (pcl::fromPCLPointCloud2 matches the type too); -1 is
  // stored as 4294967295 and read back as -1.
  for (std::size_t i = 0; i < nf; ++i) out += (labels && i + 1 == nf) ? " U" : " F";
  out += "\nCOUNT";
  for (std::size_t i = 0; i < nf; ++i) out += " 1";
  out += "\nWIDTH " + std::to_string(n) + "\nHEIGHT 1\nVIEWPOINT 0 0 0 1 0 0 0\nPOINTS " + std::to_string(n) + "\nDATA ";
  // Positions are float32 points + coordinate_offset, the type PCL's point types and pcl_viewer
  // read ("F 8" fields load as zeros into pcl::PointXYZ): far coordinates lose precision here.
  const Eigen::Vector3d& offset = cloud.coordinate_offset;
  // Float field k of point i (x y z, then the normal), each computed once: unshift formats text.
  const auto field = [&](std::size_t i, std::size_t k) -> float {
    const pcl::PointNormal& p = cloud.points[i];
    return k < 3 ? static_cast<float>(unshift(p.data[k], offset[static_cast<Eigen::Index>(k)])) : p.data_n[k - 3];
  };
  if (encoding == PcdEncoding::Ascii) {
    out += "ascii\n";
    for (std::size_t i = 0; i < n; ++i) {
      for (std::size_t k = 0; k < nfloat; ++k) {
        if (k) out += ' ';
        appendFloat(out, field(i, k));
      }
      if (colours) {
        // PCL's ascii rgb is the float whose bits are the packed colour.
        float packed;
        std::memcpy(&packed, &cloud.colours[i], sizeof packed);
        out += ' ';
        appendFloat(out, packed);
      }
      if (labels) out += ' ' + std::to_string(static_cast<std::uint32_t>(cloud.labels[i]));
      out += '\n';
    }
  } else if (encoding == PcdEncoding::Binary) {
    out += "binary\n";
    out.reserve(out.size() + n * nf * 4);
    for (std::size_t i = 0; i < n; ++i) {
      for (std::size_t k = 0; k < nfloat; ++k) appendBinary(out, field(i, k));
      if (colours) appendBinary(out, cloud.colours[i]);
      if (labels) appendBinary(out, static_cast<std::uint32_t>(cloud.labels[i]));
    }
  } else {
    out += "binary_compressed\n";
    std::string soa;
    soa.reserve(n * nf * 4);
    for (std::size_t k = 0; k < nfloat; ++k)
      for (std::size_t i = 0; i < n; ++i) appendBinary(soa, field(i, k));
    if (colours)
      for (std::size_t i = 0; i < n; ++i) appendBinary(soa, cloud.colours[i]);
    if (labels)
      for (std::size_t i = 0; i < n; ++i) appendBinary(soa, static_cast<std::uint32_t>(cloud.labels[i]));
    const std::string packed = lzfCompress(soa);
    appendBinary(out, static_cast<std::uint32_t>(packed.size()));
    appendBinary(out, static_cast<std::uint32_t>(soa.size()));
    out += packed;
  }
  return out;
}

}  // namespace paco::io::detail
