#include <paco/data/dataset.h>

#include "format.h"

#include <paco/common/error.h>
#include <paco/common/hash.h>
#include <paco/io/mesh_io.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <iomanip>
#include <sstream>

namespace paco::data {
namespace fs = std::filesystem;

double missingRatio(MissingLevel level) { return 0.25 * (static_cast<int>(level) + 1); }

std::string toString(MissingLevel level) {
  switch (level) {
    case MissingLevel::Simple: return "simple";
    case MissingLevel::Moderate: return "moderate";
    case MissingLevel::Hard: return "hard";
  }
  return "unknown";
}

std::string toString(Split split) {
  switch (split) {
    case Split::Train: return "train";
    case Split::Val: return "val";
    case Split::Test: return "test";
  }
  return "unknown";
}

Split splitFromString(const std::string& name) {
  if (name == "train") return Split::Train;
  if (name == "val") return Split::Val;
  if (name == "test") return Split::Test;
  throw InvalidInputError("unknown split '" + name + "': use train, val or test");
}

std::uint64_t fnv1a64(const std::string& text) { return fnv1a(text); }

Split splitOf(const std::string& part_name) {
  const std::uint64_t bucket = fnv1a64(part_name) % 100;
  return bucket < 80 ? Split::Train : bucket < 90 ? Split::Val : Split::Test;
}

// ---------------------------------------------------------------------------------------------
// info.tsv

namespace {

std::string joinInts(const std::vector<int>& values) {
  std::string out;
  for (std::size_t i = 0; i < values.size(); ++i) out += (i ? "," : "") + std::to_string(values[i]);
  return out;
}

std::string formatDouble(double value) {
  std::ostringstream out;
  out << std::setprecision(17) << value;
  return out.str();
}

std::vector<std::string> splitTabs(const std::string& line) {
  std::vector<std::string> fields;
  std::size_t start = 0;
  while (true) {
    const std::size_t tab = line.find('\t', start);
    fields.push_back(line.substr(start, tab == std::string::npos ? std::string::npos : tab - start));
    if (tab == std::string::npos) break;
    start = tab + 1;
  }
  return fields;
}

std::string readText(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw IoError("cannot open '" + path + "'");
  std::ostringstream text;
  text << in.rdbuf();
  return text.str();
}

}  // namespace

std::string DatasetInfo::serialize() const {
  std::ostringstream out;
  out << "format_version\t" << format_version << "\n"
      << "mode\t" << mode << "\n"
      << "levels\t" << joinInts(levels) << "\n"
      << "views\t" << views << "\n"
      << "noise_percent\t" << formatDouble(noise_percent) << "\n"
      << "augment_scale_min\t" << formatDouble(augment_scale_min) << "\n"
      << "augment_scale_max\t" << formatDouble(augment_scale_max) << "\n"
      << "augment_rotate\t" << (augment_rotate ? 1 : 0) << "\n"
      << "seed\t" << seed << "\n"
      << "input_points\t" << input_points << "\n"
      << "gt_points\t" << gt_points << "\n"
      << "dense_points\t" << dense_points << "\n"
      << "input_labels_from_segmenter\t" << (input_labels_from_segmenter ? 1 : 0) << "\n";
  // Written only when not the default, so that datasets without them keep their info file.
  if (mode == "visibility" && single_scanner) out << "single_scanner\t1\n";
  if (viewpoint_distance != 1.0) out << "viewpoint_distance\t" << formatDouble(viewpoint_distance) << "\n";
  // Only segmented inputs have a smallest plane; older readers ignore the key.
  if (input_labels_from_segmenter) out << "segment_min_points\t" << segment_min_points << "\n";
  // Written only when asked for, so that datasets without it keep their info file (and identity).
  if (input_labels_from_segmenter && segment_min_parallel_points >= 0)
    out << "segment_min_parallel_points\t" << segment_min_parallel_points << "\n";
  out << "source\t" << source << "\n";
  return out.str();
}

DatasetInfo DatasetInfo::parse(const std::string& text, const std::string& where) {
  DatasetInfo info;
  std::istringstream in(text);
  std::string line;
  bool has_version = false;
  try {
    while (std::getline(in, line)) {
      if (line.empty()) continue;
      const auto fields = splitTabs(line);
      if (fields.size() != 2) throw IoError("malformed line '" + line + "'");
      const std::string& key = fields[0];
      const std::string& value = fields[1];
      if (key == "format_version") {
        info.format_version = std::stoi(value);
        has_version = true;
      } else if (key == "mode") info.mode = value;
      else if (key == "levels") {
        info.levels.clear();
        std::istringstream list(value);
        std::string item;
        while (std::getline(list, item, ',')) info.levels.push_back(std::stoi(item));
      } else if (key == "views") info.views = std::stoi(value);
      else if (key == "single_scanner") info.single_scanner = value == "1";
      else if (key == "viewpoint_distance") info.viewpoint_distance = std::stod(value);
      else if (key == "noise_percent") info.noise_percent = std::stod(value);
      else if (key == "augment_scale_min") info.augment_scale_min = std::stod(value);
      else if (key == "augment_scale_max") info.augment_scale_max = std::stod(value);
      else if (key == "augment_rotate") info.augment_rotate = value == "1";
      else if (key == "seed") info.seed = std::stoull(value);
      else if (key == "input_points") info.input_points = std::stoi(value);
      else if (key == "gt_points") info.gt_points = std::stoi(value);
      else if (key == "dense_points") info.dense_points = std::stoi(value);
      else if (key == "input_labels_from_segmenter") info.input_labels_from_segmenter = value == "1";
      else if (key == "segment_min_points") info.segment_min_points = std::stoi(value);
      else if (key == "segment_min_parallel_points") info.segment_min_parallel_points = std::stoi(value);
      else if (key == "source") info.source = value;
      // Unknown keys are ignored: a newer writer may add information.
    }
  } catch (const std::logic_error& e) {  // stoi & co.
    throw IoError(where + ": malformed value (" + e.what() + ")");
  } catch (const IoError& e) {
    throw IoError(where + ": " + e.what());
  }
  if (!has_version) throw IoError(where + ": no format_version; is this a paco dataset info.tsv?");
  if (info.format_version != 1)
    throw IoError(where + ": dataset format v" + std::to_string(info.format_version) +
                  "; this build reads v1: rebuild the dataset with this paco_dataset");
  return info;
}

std::string DatasetInfo::describe() const {
  std::ostringstream out;
  out << "views: "
      << (mode == "visibility"
              ? "visibility (ray cast from the viewpoint, CGAL AABB tree; " +
                    std::string(single_scanner ? "one scanner" : "other cube corners add what they see") + ")"
              : std::string("nearest (AdaPoinTr: points nearest to the viewpoint removed)"))
      << "\nviewpoint distance: " << formatDouble(viewpoint_distance) << " x the diagonal, from the centre\n";
  out << "levels: ";
  for (std::size_t i = 0; i < levels.size(); ++i)
    out << (i ? ", " : "") << toString(static_cast<MissingLevel>(levels[i])) << " ("
        << static_cast<int>(std::lround(100 * missingRatio(static_cast<MissingLevel>(levels[i])))) << " % missing)";
  if (mode == "visibility" && single_scanner) out << "; with one scanner, at least that much (what it cannot see)";
  out << "\nviews per level: " << views << "\n";
  out << "noise: " << (noise_percent > 0 ? "Gaussian, sigma " + formatDouble(noise_percent) + " % of the diagonal" : "none") << "\n";
  out << "augmentation: ";
  const bool scaled = augment_scale_min != 1.0 || augment_scale_max != 1.0;
  if (!scaled && !augment_rotate) out << "none";
  if (scaled) out << "anisotropic scale per axis in [" << augment_scale_min << ", " << augment_scale_max << "]";
  if (augment_rotate) out << (scaled ? ", " : "") << "random rotation";
  out << "\ninput labels: ";
  if (!input_labels_from_segmenter) {
    out << "ground-truth faces of the visible points (not PlanarSegmenter)";
  } else {
    out << "PlanarSegmenter, planes of at least "
        << (segment_min_points > 0 ? std::to_string(segment_min_points) + " points"
                                   : std::string("the tools' rule (1 % of the input's points, 0.25 % on an input without noise since "
                                               "2026-12-07; 1 % since 2026-12-05, 1.5 % before)"));
    if (segment_min_parallel_points >= 0)
      out << ", planes parallel to a larger one of at least "
          << (segment_min_parallel_points > 0 ? std::to_string(segment_min_parallel_points) + " points"
                                              : "the tools' share of the input's points (0.15 % since 2026-12-06, "
                                                "0.5 % before and on a noisy input)");
  }
  out << "\npoints: " << input_points << " per input, " << gt_points << " ground truth, cut from " << dense_points
      << " dense\nseed: " << seed << "\nsource: " << source << "\n";
  return out.str();
}

// ---------------------------------------------------------------------------------------------
// Dataset

Dataset::Dataset(const std::string& folder) : folder_(folder) {
  const fs::path root(folder);
  if (!fs::is_directory(root)) throw IoError("dataset folder '" + folder + "' does not exist");
  const std::string info_path = (root / "info.tsv").string();
  if (!fs::exists(info_path))
    throw IoError("'" + folder + "' is not a paco dataset (no info.tsv); build one with paco_dataset");
  info_ = DatasetInfo::parse(readText(info_path), info_path);

  const std::string index_path = (root / "index.tsv").string();
  const std::string index = fs::exists(index_path) ? readText(index_path) : std::string();
  std::istringstream in(index);
  std::string line;
  std::size_t line_number = 0;
  while (std::getline(in, line)) {
    ++line_number;
    if (line_number == 1 || line.empty()) continue;  // header
    if (in.eof() && !index.empty() && index.back() != '\n') break;  // an unfinished last line
    const auto fields = splitTabs(line);
    if (fields.size() < 6)
      throw IoError(index_path + ":" + std::to_string(line_number) + ": expected 6 tab-separated fields");
    PartRecord record;
    record.part = fields[0];
    try {
      record.split = splitFromString(fields[1]);
      record.num_planes = std::stoi(fields[4]);
      record.num_samples = std::stoi(fields[5]);
    } catch (const std::exception& e) {
      throw IoError(index_path + ":" + std::to_string(line_number) + ": " + e.what());
    }
    record.file = fields[2];
    record.mesh = fields[3];
    parts_.push_back(record);
  }
  std::sort(parts_.begin(), parts_.end(), [](const PartRecord& a, const PartRecord& b) { return a.part < b.part; });

  std::vector<int> levels = info_.levels;
  const std::size_t per_part = levels.size() * static_cast<std::size_t>(info_.views);
  for (std::size_t p = 0; p < parts_.size(); ++p) {
    if (static_cast<std::size_t>(parts_[p].num_samples) != per_part)
      throw IoError(index_path + ": part '" + parts_[p].part + "' has " + std::to_string(parts_[p].num_samples) +
                    " samples, info.tsv says " + std::to_string(per_part));
    auto& list = samples_[parts_[p].split];
    for (std::size_t l = 0; l < levels.size(); ++l)
      for (int v = 0; v < info_.views; ++v)
        list.push_back({static_cast<std::uint32_t>(p), static_cast<std::uint32_t>(l * info_.views + v),
                        static_cast<std::uint8_t>(levels[l]), static_cast<std::uint8_t>(v)});
  }
}

std::size_t Dataset::size(Split split) const {
  const auto it = samples_.find(split);
  return it == samples_.end() ? 0 : it->second.size();
}

const std::string& Dataset::folder() const { return folder_; }

std::string Dataset::description() const {
  std::ostringstream out;
  out << info_.describe() << "parts: " << parts_.size() << "; samples: train " << size(Split::Train) << ", val "
      << size(Split::Val) << ", test " << size(Split::Test) << "\n";
  return out.str();
}

std::vector<std::size_t> Dataset::select(Split split, std::optional<MissingLevel> level, std::optional<int> view) const {
  std::vector<std::size_t> out;
  const auto it = samples_.find(split);
  if (it == samples_.end()) return out;
  for (std::size_t i = 0; i < it->second.size(); ++i) {
    const SampleRef& ref = it->second[i];
    if (level && ref.level != static_cast<int>(*level)) continue;
    if (view && ref.view != *view) continue;
    out.push_back(i);
  }
  return out;
}

Sample Dataset::load(Split split, std::size_t i) const {
  if (i >= size(split))
    throw InvalidInputError("Dataset::load: sample " + std::to_string(i) + " of split " + toString(split) +
                            " out of range (size " + std::to_string(size(split)) + ")");
  const SampleRef& ref = samples_.at(split)[i];
  const PartRecord& record = parts_[ref.part];
  const std::string path = (fs::path(folder_) / record.file).string();
  std::ifstream in(path, std::ios::binary);
  if (!in) throw IoError("cannot open part file '" + path + "'; the dataset is incomplete");

  char head[detail::kHeaderBytes];
  if (!in.read(head, sizeof head)) throw IoError("part file '" + path + "' is truncated (header)");
  if (std::memcmp(head, detail::kPartMagic, 8) != 0) throw IoError("'" + path + "' is not a paco part file");
  std::size_t offset = 8;
  detail::PartHeader header;
  header.version = detail::get<std::uint32_t>(head, offset);
  if (header.version != detail::kPartVersion)
    throw IoError("part file '" + path + "' has format v" + std::to_string(header.version) + "; this build reads v1");
  header.num_planes = detail::get<std::uint32_t>(head, offset);
  header.num_gt = detail::get<std::uint32_t>(head, offset);
  header.num_samples = detail::get<std::uint32_t>(head, offset);
  header.input_points = detail::get<std::uint32_t>(head, offset);
  header.flags = detail::get<std::uint32_t>(head, offset);
  for (double& c : header.center) c = detail::get<double>(head, offset);
  header.scale = detail::get<double>(head, offset);
  for (double& a : header.augmentation) a = detail::get<double>(head, offset);
  if (ref.slot >= header.num_samples || static_cast<int>(header.num_planes) != record.num_planes)
    throw IoError("part file '" + path + "' does not match index.tsv");

  // Planes and ground-truth points are contiguous: one read.
  std::string block(header.sampleOffset(0) - detail::kHeaderBytes, '\0');
  if (!in.read(block.data(), static_cast<std::streamsize>(block.size())))
    throw IoError("part file '" + path + "' is truncated (planes / ground truth)");
  std::string record_bytes(header.sampleBytes(), '\0');
  in.seekg(static_cast<std::streamoff>(header.sampleOffset(ref.slot)));
  if (!in.read(record_bytes.data(), static_cast<std::streamsize>(record_bytes.size())))
    throw IoError("part file '" + path + "' is truncated (sample " + std::to_string(ref.slot) + ")");

  Sample s;
  s.part = record.part;
  s.gt_mesh_path = (fs::path(folder_) / record.mesh).string();
  s.normalization.center = Eigen::Vector3d(header.center[0], header.center[1], header.center[2]);
  s.normalization.scale = header.scale;
  for (int k = 0; k < 9; ++k) s.augmentation(k / 3, k % 3) = header.augmentation[k];
  s.input_labels_from_segmenter = (header.flags & 1u) != 0;

  offset = 0;
  const char* data = block.data();
  for (std::uint32_t p = 0; p < header.num_planes; ++p) {
    Eigen::Vector3d n;
    for (int k = 0; k < 3; ++k) n[k] = detail::get<double>(data, offset);
    const double d = detail::get<double>(data, offset);
    s.gt_planes.emplace_back(n, d);
    s.gt_plane_areas.push_back(detail::get<double>(data, offset));
  }
  auto readPoints = [](const char* bytes, std::size_t& at, std::size_t count, pcl::PointCloud<pcl::PointNormal>& cloud,
                       std::vector<int>& labels) {
    cloud.resize(count);
    labels.resize(count);
    for (std::size_t j = 0; j < count; ++j) {
      float row[7];
      std::memcpy(row, bytes + at, sizeof row);
      at += sizeof row;
      pcl::PointNormal& q = cloud[j];
      q.x = row[0]; q.y = row[1]; q.z = row[2];
      q.normal_x = row[3]; q.normal_y = row[4]; q.normal_z = row[5];
      q.curvature = 0.0f;
      labels[j] = static_cast<int>(std::lround(row[6]));
    }
  };
  readPoints(data, offset, header.num_gt, s.gt_points, s.gt_labels);

  const char* rec = record_bytes.data();
  offset = 0;
  const std::uint32_t level = detail::get<std::uint32_t>(rec, offset);
  s.view = static_cast<int>(detail::get<std::uint32_t>(rec, offset));
  for (int k = 0; k < 3; ++k) s.viewpoint[k] = detail::get<float>(rec, offset);
  s.missing_ratio = detail::get<float>(rec, offset);
  if (level > 2 || level != ref.level || s.view != ref.view)
    throw IoError("part file '" + path + "': sample " + std::to_string(ref.slot) + " is not the one index.tsv implies");
  s.level = static_cast<MissingLevel>(level);
  readPoints(rec, offset, header.input_points, s.input, s.input_labels);
  return s;
}

paco::SurfaceMesh Dataset::loadGtMesh(const Sample& s) const { return io::loadMesh(s.gt_mesh_path); }

}  // namespace paco::data
