#include <paco/data/builder.h>

#include "format.h"
#include "random.h"

#include <paco/common/error.h>
#include <paco/common/scan_shares.h>
#include <paco/io/mesh_io.h>

#include <Eigen/Geometry>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <sstream>

#ifdef PACO_DATA_WITH_SEGMENTATION
#include <paco/segmentation/planar_segmenter.h>
#endif

namespace paco::data {
namespace fs = std::filesystem;

bool segmentationAvailable() {
#ifdef PACO_DATA_WITH_SEGMENTATION
  return true;
#else
  return false;
#endif
}

Eigen::Matrix3d augmentationFor(const std::string& part, const DatasetInfo& info) {
  detail::Rng rng(detail::mixSeed(info.seed ^ fnv1a64(part), 7));
  Eigen::Matrix3d scale = Eigen::Matrix3d::Identity();
  if (info.augment_scale_min != 1.0 || info.augment_scale_max != 1.0) {
    if (!(info.augment_scale_min > 0.0 && info.augment_scale_max >= info.augment_scale_min))
      throw InvalidInputError("augmentation scale range must satisfy 0 < min <= max");
    // Log-uniform, so that a range like [0.5, 2] stretches and squeezes equally often.
    const double lo = std::log(info.augment_scale_min), hi = std::log(info.augment_scale_max);
    for (int a = 0; a < 3; ++a) scale(a, a) = std::exp(rng.uniform(lo, hi));
  }
  Eigen::Matrix3d rotation = Eigen::Matrix3d::Identity();
  if (info.augment_rotate) {
    // A uniformly random rotation: a normalised 4D Gaussian quaternion.
    Eigen::Quaterniond q(rng.normal(), rng.normal(), rng.normal(), rng.normal());
    q.normalize();
    rotation = q.toRotationMatrix();
  }
  return rotation * scale;
}

PartSamples buildPart(const std::string& part, const SurfaceMesh& mesh, const BuildOptions& options) {
  const DatasetInfo& info = options.info;
  if (info.levels.empty() || info.views <= 0) throw InvalidInputError("buildPart: no levels or no views asked");
  if (options.segment && !segmentationAvailable())
    throw InvalidInputError("--segment needs the segmentation module; rebuild paco with it enabled");
  if (options.segment && info.segment_min_points < 0)
    throw InvalidInputError("segment_min_points must be >= 0 (0: " + percentText(kScanMinPlaneFraction) +
                            " of each input's points)");
  mesh.validate(part);

  PartSamples out;
  out.part = part;
  out.augmentation = augmentationFor(part, info);
  SurfaceMesh work = mesh;
  for (auto& v : work.vertices) v = out.augmentation * v;
  out.normalization = Normalization::fromBoundingBox(work.vertices);
  out.normalization.apply(work);
  out.ground_truth = extractGroundTruth(work, options.ground_truth);

  const std::uint64_t base = detail::mixSeed(info.seed, fnv1a64(part));
  out.gt = sampleGroundTruth(out.ground_truth, static_cast<std::size_t>(info.gt_points), detail::mixSeed(base, 1));

  PartialOptions partial;
  partial.mode = removalModeFromString(info.mode);
  partial.dense_points = static_cast<std::size_t>(info.dense_points);
  partial.output_points = static_cast<std::size_t>(info.input_points);
  partial.noise_percent = info.noise_percent;
  partial.single_scanner = info.single_scanner;
  partial.viewpoint_distance = info.viewpoint_distance;
  const PartialScanner scanner(out.ground_truth, partial, detail::mixSeed(base, 2));

  for (int level : info.levels) {
    if (level < 0 || level > 2) throw InvalidInputError("level " + std::to_string(level) + " is not 0, 1 or 2");
    for (int view = 0; view < info.views; ++view) {
      PartialSample sample;
      sample.level = static_cast<MissingLevel>(level);
      sample.view = view;
      sample.viewpoint = viewpointDirection(view, info.views);
      PartialScan scan = scanner.scan(sample.viewpoint, missingRatio(sample.level),
                                      detail::mixSeed(base, 1000 + 100 * static_cast<std::uint64_t>(level) + view));
      sample.missing_ratio = scan.missing_ratio;
      sample.points = std::move(scan.points);
      sample.normals = std::move(scan.normals);
      sample.labels = std::move(scan.labels);
#ifdef PACO_DATA_WITH_SEGMENTATION
      if (options.segment) {
        auto cloud = pcl::make_shared<pcl::PointCloud<pcl::PointNormal>>();
        for (std::size_t i = 0; i < sample.points.size(); ++i) {
          pcl::PointNormal q;
          q.x = static_cast<float>(sample.points[i].x());
          q.y = static_cast<float>(sample.points[i].y());
          q.z = static_cast<float>(sample.points[i].z());
          q.normal_x = static_cast<float>(sample.normals[i].x());
          q.normal_y = static_cast<float>(sample.normals[i].y());
          q.normal_z = static_cast<float>(sample.normals[i].z());
          cloud->push_back(q);
        }
        auto segmenter = makePlanarSegmenter<pcl::PointNormal>("gocopp");
        segmenter->setInputCloud(cloud);
        segmenter->setNumberOfThreads(1);
        setScanDefaults(*segmenter, cloud->size(), info.segment_min_points, info.segment_min_parallel_points);
        PlanarSegmentation segmentation;
        segmenter->segment(segmentation);
        sample.labels = segmentation.labels;
      }
#endif
      out.samples.push_back(std::move(sample));
    }
  }
  out.labels_from_segmenter = options.segment;
  return out;
}

std::string encodePartFile(const PartSamples& part) {
  using detail::put;
  detail::PartHeader header;
  header.num_planes = static_cast<std::uint32_t>(part.ground_truth.faces.size());
  header.num_gt = static_cast<std::uint32_t>(part.gt.points.size());
  header.num_samples = static_cast<std::uint32_t>(part.samples.size());
  header.input_points = part.samples.empty() ? 0 : static_cast<std::uint32_t>(part.samples.front().points.size());
  header.flags = part.labels_from_segmenter ? 1u : 0u;

  std::string out;
  out.reserve(header.fileBytes());
  out.append(detail::kPartMagic, 8);
  put<std::uint32_t>(out, header.version);
  put<std::uint32_t>(out, header.num_planes);
  put<std::uint32_t>(out, header.num_gt);
  put<std::uint32_t>(out, header.num_samples);
  put<std::uint32_t>(out, header.input_points);
  put<std::uint32_t>(out, header.flags);
  for (int k = 0; k < 3; ++k) put<double>(out, part.normalization.center[k]);
  put<double>(out, part.normalization.scale);
  for (int k = 0; k < 9; ++k) put<double>(out, part.augmentation(k / 3, k % 3));
  for (const PlanarFace& face : part.ground_truth.faces) {
    for (int k = 0; k < 3; ++k) put<double>(out, face.plane.normal[k]);
    put<double>(out, face.plane.offset);
    put<double>(out, face.area);
  }
  auto putPoint = [&out](const Eigen::Vector3d& p, const Eigen::Vector3d& n, int label) {
    for (int k = 0; k < 3; ++k) put<float>(out, static_cast<float>(p[k]));
    for (int k = 0; k < 3; ++k) put<float>(out, static_cast<float>(n[k]));
    put<float>(out, static_cast<float>(label));
  };
  for (std::size_t i = 0; i < part.gt.points.size(); ++i) putPoint(part.gt.points[i], part.gt.normals[i], part.gt.labels[i]);
  for (const PartialSample& s : part.samples) {
    if (s.points.size() != header.input_points) throw InvalidInputError("encodePartFile: samples differ in size");
    put<std::uint32_t>(out, static_cast<std::uint32_t>(s.level));
    put<std::uint32_t>(out, static_cast<std::uint32_t>(s.view));
    for (int k = 0; k < 3; ++k) put<float>(out, static_cast<float>(s.viewpoint[k]));
    put<float>(out, static_cast<float>(s.missing_ratio));
    for (std::size_t i = 0; i < s.points.size(); ++i) putPoint(s.points[i], s.normals[i], s.labels[i]);
  }
  if (out.size() != header.fileBytes()) throw Error("encodePartFile: internal size mismatch");
  return out;
}

// ---------------------------------------------------------------------------------------------
// DatasetWriter

namespace {

const char* kIndexHeader = "part\tsplit\tfile\tmesh\tplanes\tsamples\n";
const char* kFailuresHeader = "part\treason\n";

std::string readAll(const fs::path& path) {
  std::ifstream in(path, std::ios::binary);
  std::ostringstream text;
  text << in.rdbuf();
  return text.str();
}

void writeAtomically(const fs::path& path, const std::string& bytes) {
  const fs::path temp = path.string() + ".partial";
  {
    std::ofstream out(temp, std::ios::binary | std::ios::trunc);
    if (!out.write(bytes.data(), static_cast<std::streamsize>(bytes.size())) || !out.flush())
      throw IoError("cannot write '" + temp.string() + "' (disk full or no permission?)");
  }
  std::error_code error;
  fs::rename(temp, path, error);
  if (error) throw IoError("cannot rename '" + temp.string() + "' to '" + path.string() + "': " + error.message());
}

/// Reads the first column of a TSV with a header; drops an unfinished last line (an interrupted
/// append) by truncating the file to its last complete line.
std::set<std::string> readNames(const fs::path& path, const char* header) {
  std::set<std::string> names;
  if (!fs::exists(path)) {
    writeAtomically(path, header);
    return names;
  }
  std::string text = readAll(path);
  if (!text.empty() && text.back() != '\n') {
    text.erase(text.rfind('\n') == std::string::npos ? 0 : text.rfind('\n') + 1);
    writeAtomically(path, text.empty() ? std::string(header) : text);
  }
  std::istringstream in(text);
  std::string line;
  std::getline(in, line);  // header
  while (std::getline(in, line))
    if (!line.empty()) names.insert(line.substr(0, line.find('\t')));
  return names;
}

void appendLine(const fs::path& path, const std::string& line) {
  // One write of the whole line, flushed at once: a crash leaves at most an unfinished last
  // line, which the next open drops.
  std::FILE* file = std::fopen(path.c_str(), "ab");
  if (!file) throw IoError("cannot append to '" + path.string() + "'");
  const bool ok = std::fwrite(line.data(), 1, line.size(), file) == line.size() && std::fflush(file) == 0;
  std::fclose(file);
  if (!ok) throw IoError("cannot append to '" + path.string() + "' (disk full?)");
}

std::string sanitize(std::string text) {
  for (char& c : text)
    if (c == '\t' || c == '\n' || c == '\r') c = ' ';
  return text;
}

}  // namespace

DatasetWriter::DatasetWriter(const std::string& folder, const DatasetInfo& info) : folder_(folder) {
  const fs::path root(folder);
  std::error_code error;
  fs::create_directories(root / "parts", error);
  fs::create_directories(root / "meshes", error);
  if (!fs::is_directory(root / "parts") || !fs::is_directory(root / "meshes"))
    throw IoError("cannot create the dataset folder '" + folder + "'");
  const fs::path info_path = root / "info.tsv";
  if (fs::exists(info_path)) {
    const DatasetInfo existing = DatasetInfo::parse(readAll(info_path), info_path.string());
    DatasetInfo a = existing, b = info;
    a.source = b.source = "";  // the same dataset may be resumed from another path
    if (a.serialize() != b.serialize())
      throw IoError("'" + folder + "' holds a dataset made with other options:\n" + existing.describe() +
                    "resume it with the same options, or write to a new folder");
  } else {
    writeAtomically(info_path, info.serialize());
  }
  finished_ = readNames(root / "index.tsv", kIndexHeader);
  failed_ = readNames(root / "failures.tsv", kFailuresHeader);
}

bool DatasetWriter::isDone(const std::string& part) const {
  std::lock_guard<std::mutex> lock(mutex_);
  return finished_.count(part) > 0 || failed_.count(part) > 0;
}

std::size_t DatasetWriter::numFinished() const {
  std::lock_guard<std::mutex> lock(mutex_);
  return finished_.size();
}

std::size_t DatasetWriter::numFailed() const {
  std::lock_guard<std::mutex> lock(mutex_);
  return failed_.size();
}

void DatasetWriter::write(const PartSamples& part) {
  if (part.part.empty() || part.part.find_first_of("\t\n\r/\\") != std::string::npos)
    throw InvalidInputError("part name '" + part.part + "' is empty or has tabs, newlines or slashes");
  const fs::path root(folder_);
  const std::string file = "parts/" + part.part + ".bin";
  const std::string mesh = "meshes/" + part.part + ".off";
  writeAtomically(root / file, encodePartFile(part));
  // The GT mesh in the normalised frame; saveMesh picks the format by the extension.
  const fs::path mesh_temp = root / ("meshes/" + part.part + ".partial.off");
  io::saveMesh(mesh_temp.string(), part.ground_truth.mesh);
  std::error_code error;
  fs::rename(mesh_temp, root / mesh, error);
  if (error) throw IoError("cannot rename '" + mesh_temp.string() + "': " + error.message());

  std::ostringstream line;
  line << part.part << '\t' << toString(splitOf(part.part)) << '\t' << file << '\t' << mesh << '\t'
       << part.ground_truth.faces.size() << '\t' << part.samples.size() << '\n';
  std::lock_guard<std::mutex> lock(mutex_);
  appendLine(root / "index.tsv", line.str());
  finished_.insert(part.part);
}

void DatasetWriter::fail(const std::string& part, const std::string& reason) {
  std::lock_guard<std::mutex> lock(mutex_);
  appendLine(fs::path(folder_) / "failures.tsv", sanitize(part) + '\t' + sanitize(reason) + '\n');
  failed_.insert(part);
}

}  // namespace paco::data
