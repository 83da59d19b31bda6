#pragma once
// NumPy .npy arrays in the authors' layout: N rows x 7 columns (x, y, z, nx, ny, nz, plane_id),
// float32 or float64, C order, little-endian. Readers also take N x 3 and N x 6.
// Usage:
//   paco::io::NpyArray a = paco::io::loadNpy("sample.npy");   // a.rows, a.cols, a.data (row-major)
#include <cstddef>
#include <string>
#include <vector>

namespace paco::io {

struct NpyArray {
  std::size_t rows = 0, cols = 0;
  std::vector<double> data;  ///< row-major, rows * cols values
  double at(std::size_t r, std::size_t c) const { return data[r * cols + c]; }
};

/// Reads a 2-D (or 1-D: one column) float32/float64 .npy, format v1, v2 or v3, either byte order,
/// C or Fortran order. Throws paco::IoError for a bad magic, an unsupported dtype or shape, a
/// malformed header dict, or a file shorter than its header says.
NpyArray loadNpy(const std::string& path);
/// Writes a 2-D array as float32 ("<f4") or float64 ("<f8").
void saveNpy(const std::string& path, const NpyArray& array, bool float64 = false);

}  // namespace paco::io
