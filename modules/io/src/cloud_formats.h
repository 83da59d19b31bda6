#pragma once
// Internal: the per-format cloud readers and writers behind loadCloud / saveCloud. Readers get the
// whole file in memory and fail with IoError naming `path`; writers return the file's bytes.
#include <paco/io/cloud_io.h>

#include <string>

namespace paco::io::detail {

LabelledCloud readPcd(const std::string& path, const std::string& bytes);
std::string writePcd(const LabelledCloud& cloud, PcdEncoding encoding);

LabelledCloud readPlyCloud(const std::string& path, const std::string& bytes);
std::string writePlyCloud(const LabelledCloud& cloud, bool ascii);

LabelledCloud readXyz(const std::string& path, const std::string& bytes);
std::string writeXyz(const LabelledCloud& cloud);

/// Checks that label values are integers in int range; fails otherwise.
int labelFromValue(const std::string& path, double value, std::size_t point);

}  // namespace paco::io::detail
