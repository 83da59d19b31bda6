#pragma once
// Internal: LZF (the compression of PCD's binary_compressed data), so that paco::io does not
// link pcl_io, whose imported target drags in VTK, Qt and MPI.
#include <cstddef>
#include <string>
#include <string_view>

namespace paco::io::detail {

/// Compresses `in` to an LZF stream (always succeeds; incompressible data grows by ~3%).
std::string lzfCompress(std::string_view in);
/// Decompresses an LZF stream that must expand to exactly `expected_size` bytes; false when the
/// stream is corrupt (bad back-reference, overrun, or a different size).
bool lzfDecompress(std::string_view in, std::size_t expected_size, std::string& out);

}  // namespace paco::io::detail
