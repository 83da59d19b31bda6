#pragma once
// Internal: a small, bounds-checked PLY reader (ascii, binary little- and big-endian) used by the
// cloud and mesh readers, and the header text for the writers.
#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

namespace paco::io::detail {

enum class PlyType { Int8, UInt8, Int16, UInt16, Int32, UInt32, Float32, Float64 };

struct PlyProperty {
  std::string name;
  PlyType type = PlyType::Float32;  ///< value type (of the items for a list)
  bool is_list = false;
  PlyType count_type = PlyType::UInt8;
};

/// One element (vertex, face, ...) with its values: scalars[p] holds the p-th property's values of
/// every record (empty for list properties); lists hold the list properties' items and offsets.
struct PlyElement {
  std::string name;
  std::size_t count = 0;
  std::vector<PlyProperty> properties;
  std::vector<std::vector<double>> scalars;
  std::vector<std::vector<double>> list_items;             ///< per property: all items
  std::vector<std::vector<std::size_t>> list_offsets;      ///< per property: count + 1 offsets

  /// Index of the first property with one of these names, or -1.
  int find(std::initializer_list<const char*> names) const;
};

struct PlyFile {
  std::vector<PlyElement> elements;
  const PlyElement* element(const std::string& name) const;
};

/// Parses a whole PLY file already in memory; fails with IoError naming `path` and the problem.
PlyFile readPly(const std::string& path, const std::string& bytes);

const char* plyTypeName(PlyType type);

}  // namespace paco::io::detail
