#include "app_support.h"

#include <paco/common/allocator.h>
#include <paco/common/error.h>
#include <paco/common/primitive.h>
#include <paco/common/surface_mesh.h>
#include <paco/io/cloud_io.h>

#include <fcntl.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <iostream>
#include <limits>
#include <map>
#include <c10/util/Exception.h>

#include <new>
#include <sstream>
#include <stdexcept>
#include <thread>

namespace paco::app {

int runTool(const std::string& tool_name, const std::function<int()>& body) {
  paco::keepFreedMemoryForReuse();  // LibTorch's tensors then cost no page faults each time
  try {
    return body();
  } catch (...) {
    return reportCurrentException(tool_name);
  }
}

int reportCurrentException(const std::string& tool_name, const std::string& subject) {
  const std::string about = subject.empty() ? std::string() : "'" + subject + "': ";
  try {
    throw;
  } catch (const UsageError& e) {
    std::cerr << tool_name << ": " << e.what() << "\nTry '" << tool_name << " --help'." << std::endl;
    return 2;
  } catch (const paco::InterruptedError& e) {
    // Ctrl-C (or SIGTERM) honoured at a stage boundary, before any output is committed: 130, as a
    // shell reports SIGINT and as paco_train and paco_dataset end an interrupted run.
    std::cerr << tool_name << ": " << e.what() << "; nothing written" << std::endl;
    return 130;
  } catch (const paco::Error& e) {
    std::cerr << tool_name << ": error: " << e.what() << std::endl;  // paco's messages name their file
    return 1;
  } catch (const c10::Error& e) {
    // LibTorch's own message (e.g. "not enough memory: you tried to allocate ..."), without the
    // stack trace of LibTorch's frames that what() appends.
    std::cerr << tool_name << ": error: " << about << e.what_without_backtrace() << std::endl;
    return 1;
  } catch (const std::bad_alloc&) {
    std::cerr << tool_name << ": error: " << about << "out of memory; try a smaller input or smaller settings"
              << std::endl;
    return 1;
  } catch (const std::exception& e) {
    std::cerr << tool_name << ": error: " << about << e.what() << std::endl;
    return 1;
  }
}

void exitSkippingTeardown(int code) {
  std::cout.flush();
  std::cerr.flush();
  std::fflush(nullptr);
#ifdef PACO_SANITIZER_ALLOCATOR
  std::exit(code);
#else
  std::_Exit(code);
#endif
}

namespace {
bool isUnsigned(const boost::program_options::value_semantic* semantic) {
  namespace po = boost::program_options;
  return dynamic_cast<const po::typed_value<unsigned short>*>(semantic) ||
         dynamic_cast<const po::typed_value<unsigned int>*>(semantic) ||
         dynamic_cast<const po::typed_value<unsigned long>*>(semantic) ||
         dynamic_cast<const po::typed_value<unsigned long long>*>(semantic);
}

// program_options reads "-1" into an unsigned option as its wrap-around (18446744073709551615 for
// --max-points): a count given with a minus sign is refused instead.
void rejectNegativeUnsigned(const boost::program_options::parsed_options& parsed,
                            const boost::program_options::options_description& options) {
  for (const auto& option : parsed.options) {
    const auto* description = options.find_nothrow(option.string_key, false);
    if (!description || !isUnsigned(description->semantic().get())) continue;
    for (const std::string& text : option.value)
      if (text.find('-') != std::string::npos)
        throw UsageError("--" + option.string_key + " must be a whole number >= 0, got '" + text + "'");
  }
}
}  // namespace

boost::program_options::variables_map parseCommandLine(
    int argc, char** argv, const boost::program_options::options_description& options,
    const boost::program_options::positional_options_description& positional) {
  namespace po = boost::program_options;
  po::variables_map vm;
  try {
    const po::parsed_options parsed = po::command_line_parser(argc, argv).options(options).positional(positional).run();
    rejectNegativeUnsigned(parsed, options);
    po::store(parsed, vm);
    po::notify(vm);
  } catch (const po::error& e) {
    throw UsageError(e.what());
  }
  return vm;
}

double parseNonNegativeOrOff(const std::string& option, const std::string& text) {
  if (text == "off") return std::numeric_limits<double>::infinity();
  std::size_t used = 0;
  double value = std::numeric_limits<double>::quiet_NaN();
  try {
    value = std::stod(text, &used);
  } catch (const std::exception&) {
    used = 0;
  }
  if (used != text.size() || !std::isfinite(value) || value < 0.0)
    throw UsageError(option + " must be a number >= 0 or 'off', got '" + text + "'");
  return value;
}

unsigned maxThreads() {
  // More threads than cores only add contention and start-up time (1000 threads took 42 s on two
  // cores, 100000 never finished); 4 per hardware thread leaves room for I/O waits.
  const unsigned hardware = std::thread::hardware_concurrency();
  return hardware == 0 ? 256u : 4u * hardware;
}

void validateThreads(const std::string& option, long long threads, const std::string& zero_meaning) {
  const long long most = maxThreads();
  if ((threads == 0 && !zero_meaning.empty()) || (threads >= 1 && threads <= most)) return;
  throw UsageError(option + " must be " + (zero_meaning.empty() ? "" : "0 (" + zero_meaning + ") or ") + "1 to " +
                   std::to_string(most) + " (4 per hardware thread), got " + std::to_string(threads));
}

namespace {
// Whether two paths name the same file: the same path once links and ".." are resolved, or two
// names of one existing file (a hard link).
bool sameFile(const std::string& a, const std::string& b) {
  namespace fs = std::filesystem;
  std::error_code ec_a, ec_b, ec;
  const fs::path canonical_a = fs::weakly_canonical(fs::absolute(a, ec_a), ec_a);
  const fs::path canonical_b = fs::weakly_canonical(fs::absolute(b, ec_b), ec_b);
  if (!ec_a && !ec_b && canonical_a == canonical_b) return true;
  return fs::exists(a, ec) && fs::exists(b, ec) && fs::equivalent(a, b, ec) && !ec;
}

std::string temporaryName(const std::string& final_path) {
  const std::filesystem::path p(final_path);
  // "mesh.obj" -> "mesh.partial.obj": the extension stays last so writers still pick the format.
  return (p.parent_path() / (p.stem().string() + ".partial" + p.extension().string())).string();
}
}  // namespace

void checkOutputsAreNotInputs(const std::vector<FileArgument>& inputs, const std::vector<FileArgument>& outputs) {
  for (std::size_t o = 0; o < outputs.size(); ++o) {
    const FileArgument& output = outputs[o];
    if (output.path.empty()) continue;
    for (const FileArgument& input : inputs) {
      if (input.path.empty()) continue;
      if (sameFile(output.path, input.path))
        throw UsageError(output.option + " '" + output.path + "' is the same file as " + input.option + " '" +
                         input.path + "': writing it would replace that input; give " + output.option +
                         " another file name");
      const std::string temporary = temporaryName(output.path);
      if (sameFile(temporary, input.path))
        throw UsageError(output.option + " '" + output.path + "' is written to '" + temporary + "' first, which is " +
                         input.option + " '" + input.path + "'; give " + output.option + " another file name");
    }
    for (std::size_t earlier = 0; earlier < o; ++earlier)
      if (!outputs[earlier].path.empty() && sameFile(output.path, outputs[earlier].path))
        throw UsageError(output.option + " '" + output.path + "' is the same file as " + outputs[earlier].option +
                         " '" + outputs[earlier].path + "'; give each output its own file name");
  }
}

void reportCoordinateOffset(const Eigen::Vector3d& offset) {
  if (offset.isZero(0.0)) return;
  // The offset is a tidy number (5412300), which %.15g prints in full.
  std::printf("coordinates far from 0 for the scan's size: working relative to (%.15g, %.15g, %.15g) to keep "
              "float32 precision; outputs are written in the input's coordinates\n",
              offset.x(), offset.y(), offset.z());
}

void warnIfPcdRoundsFarCoordinates(const std::string& path, const Eigen::Vector3d& offset) {
  if (offset.isZero(0.0) || io::extensionOf(path) != ".pcd") return;
  // float32 rounds to within 2^-24 of a value; the offset is about the largest coordinate.
  std::fprintf(stderr,
               "warning: '%s' stores float32 positions (the type PCL reads), which round coordinates this far "
               "from 0 by up to %.2g; write .ply, .xyz or .npy to keep full precision\n",
               path.c_str(), offset.cwiseAbs().maxCoeff() * 0x1p-24);
}

void moveToFileCoordinates(SurfaceMesh& mesh, const Eigen::Vector3d& offset) {
  for (Eigen::Vector3d& v : mesh.vertices) v += offset;
}

double reachBeyondBox(const SurfaceMesh& mesh, const Eigen::AlignedBox3d& box, const Eigen::Matrix3d& axes) {
  if (box.isEmpty()) return 0.0;
  const double diagonal = box.diagonal().norm();
  if (!(diagonal > 0.0)) return 0.0;
  double farthest = 0.0;
  for (const Eigen::Vector3d& v : mesh.vertices)
    farthest = std::max(farthest, box.exteriorDistance(Eigen::Vector3d(axes.transpose() * v)));
  return farthest / diagonal;
}

std::string farReachNote(double reach, double diagonal) {
  if (!(reach > kFarReach)) return "";
  const auto shortLength = [](double length) {
    char number[32];
    std::snprintf(number, sizeof(number), "%.3g", length);
    return std::string(number);
  };
  char text[512];
  std::snprintf(text, sizeof(text),
                "the mesh reaches %s (%.0f %% of the scan's diagonal) beyond the scan's bounding box: that much "
                "of it is the completion's guess of the unseen side. If the object cannot reach that far, say how "
                "it was scanned (--seen-from, --seen-from-point) or where it ends (--known-extent); doc/usage.md",
                shortLength(reach * diagonal).c_str(), 100.0 * reach);
  return text;
}

PlanarSegmentation segmentationFromLabels(const io::LabelledCloud& cloud, const std::string& path) {
  // Labels may be any integers: number them 0..K-1 in order of appearance.
  std::map<int, int> segment_of;
  std::vector<int> label_of_segment;
  PlanarSegmentation segmentation;
  segmentation.labels.assign(cloud.labels.size(), -1);
  for (std::size_t i = 0; i < cloud.labels.size(); ++i) {
    if (cloud.labels[i] < 0) continue;
    const auto inserted = segment_of.emplace(cloud.labels[i], static_cast<int>(segment_of.size()));
    if (inserted.second) label_of_segment.push_back(cloud.labels[i]);
    segmentation.labels[i] = inserted.first->second;
  }
  segmentation.planes.resize(segment_of.size());
  segmentation.rebuildSegmentsFromLabels();
  for (std::size_t k = 0; k < segmentation.segments.size(); ++k) {
    std::vector<Eigen::Vector3d> points;
    Eigen::Vector3d mean_normal = Eigen::Vector3d::Zero();
    for (int i : segmentation.segments[k].indices) {
      const auto& p = cloud.points[static_cast<std::size_t>(i)];
      points.emplace_back(p.x, p.y, p.z);
      mean_normal += Eigen::Vector3d(p.normal_x, p.normal_y, p.normal_z);
    }
    if (points.size() < 3)
      throw InvalidInputError("label " + std::to_string(label_of_segment[k]) + " of '" + path + "' has " +
                              std::to_string(points.size()) + (points.size() == 1 ? " point" : " points") +
                              "; a plane needs at least 3: relabel them, or label them -1 (no plane)");
    segmentation.planes[k] = Plane::fit(points, mean_normal);
  }
  return segmentation;
}

std::string noisyScanNote(double set, double used) {
  if (!(used > set)) return {};
  char text[96];
  std::snprintf(text, sizeof text, ", inlier distance raised to %.4f of the diagonal: the scan is noisy", used);
  return text;
}

std::string exactScanNote(int set, int used) {
  if (!(used < set)) return {};
  return " (" + std::to_string(set) + " on a scan with noise)";
}

void addNoiseAdaptationOption(boost::program_options::options_description& options, double& multiple) {
  options.add_options()("noise-adaptation",
                        boost::program_options::value(&multiple)->default_value(multiple, shortNumber(multiple)),
                        "segmenter: on a noisy scan, widen the inlier distance to this many times the estimated noise "
                        "(0: off)");
}

void validateNoiseAdaptation(double multiple) {
  if (!(multiple >= 0.0 && std::isfinite(multiple)))
    throw UsageError("--noise-adaptation must be 0 (off) or a positive number, got " + shortNumber(multiple));
}

std::string shortNumber(double value) {
  std::ostringstream text;
  text << value;
  return text.str();
}

FusionFlags::FusionFlags(double align_unseen_degrees, double clip_margin, double tilt_margin, double fill_box_spacing,
                         double unseen_point_fraction, double contradiction_radius, double join_distance)
    : align_unseen_degrees(align_unseen_degrees),
      clip_margin(std::isinf(clip_margin) ? "off" : shortNumber(clip_margin)),
      tilt_margin(std::isinf(tilt_margin) ? "off" : shortNumber(tilt_margin)),
      fill_box_spacing(fill_box_spacing),
      unseen_point_fraction(unseen_point_fraction),
      contradiction_radius(contradiction_radius),
      join_distance(join_distance) {}

void FusionFlags::addTo(boost::program_options::options_description& options) {
  namespace po = boost::program_options;
  options.add_options()
      ("align-unseen", po::value(&align_unseen_degrees)->default_value(align_unseen_degrees, shortNumber(align_unseen_degrees)),
       "with fusion: turn unseen primitives within this many degrees of a seen direction parallel to it (0: off)")
      ("clip-margin", po::value(&clip_margin)->default_value(clip_margin),
       "with fusion: drop completed points beyond the box of the seen points plus this fraction of its diagonal (off: keep all)")
      ("tilt-margin", po::value(&tilt_margin)->default_value(tilt_margin),
       "with fusion, when no two seen planes are perpendicular (a roof seen from above): a seen face tilted against "
       "the box keeps the network's points only within this fraction of the diagonal of the box along the axes it "
       "tilts towards (off: keep all)")
      ("fill-box", po::value(&fill_box_spacing)->default_value(fill_box_spacing, shortNumber(fill_box_spacing)),
       "with fusion: cover the uncovered faces of the box of the seen points with points this far apart (fraction of its diagonal; 0: off)")
      ("unseen-points", po::value(&unseen_point_fraction)->default_value(unseen_point_fraction, shortNumber(unseen_point_fraction)),
       "with fusion: the fraction of the network's points that unseen primitives keep, in (0, 1] (1: all)")
      ("contradiction-radius", po::value(&contradiction_radius)->default_value(contradiction_radius, shortNumber(contradiction_radius)),
       "with fusion: drop the network's points of a seen face where the scan, within this fraction of the diagonal, "
       "saw no such face, shows solid, or shows air where the face has solid (0: off)")
      ("join-distance", po::value(&join_distance)->default_value(join_distance, shortNumber(join_distance)),
       "with fusion: a seen segment joins another seen face's primitive only when its points lie this close to "
       "that face's plane on average (fraction of the diagonal); a parallel face farther off keeps its own plane");
}

void FusionFlags::validate() const {
  if (!(align_unseen_degrees >= 0.0 && align_unseen_degrees < 90.0))
    throw UsageError("--align-unseen must be in [0, 90) degrees, got " + shortNumber(align_unseen_degrees));
  // 0.001 is paco::kMinFillSpacing; app_support does not depend on the completion module.
  if (!(fill_box_spacing == 0.0 || (fill_box_spacing >= 0.001 && fill_box_spacing < 1.0)))
    throw UsageError("--fill-box must be 0 (off) or in [0.001, 1) (a fraction of the diagonal), got " +
                     shortNumber(fill_box_spacing));
  if (!(unseen_point_fraction > 0.0 && unseen_point_fraction <= 1.0))
    throw UsageError("--unseen-points must be in (0, 1] (a fraction of the points), got " +
                     shortNumber(unseen_point_fraction));
  if (!(contradiction_radius >= 0.0 && contradiction_radius < 1.0))
    throw UsageError("--contradiction-radius must be 0 (off) or in (0, 1) (a fraction of the diagonal), got " +
                     shortNumber(contradiction_radius));
  if (!(join_distance >= 0.0 && join_distance < 1.0))
    throw UsageError("--join-distance must be in [0, 1) (a fraction of the diagonal), got " +
                     shortNumber(join_distance));
  parseNonNegativeOrOff("--clip-margin", clip_margin);
  parseNonNegativeOrOff("--tilt-margin", tilt_margin);
}

double FusionFlags::clipMargin() const {
  validate();
  return parseNonNegativeOrOff("--clip-margin", clip_margin);
}

double FusionFlags::tiltMargin() const {
  validate();
  return parseNonNegativeOrOff("--tilt-margin", tilt_margin);
}

void checkOutputPath(const std::string& path, const std::string& option, const std::vector<std::string>& extensions) {
  namespace fs = std::filesystem;
  if (!extensions.empty()) {
    const std::string ext = paco::io::extensionOf(path);
    if (std::find(extensions.begin(), extensions.end(), ext) == extensions.end()) {
      std::string list;
      for (std::size_t i = 0; i < extensions.size(); ++i)
        list += (i == 0 ? "" : i + 1 == extensions.size() ? " or " : ", ") + extensions[i];
      throw UsageError(option + " must name a " + list + " file, got '" + path + "'");
    }
  }
  std::error_code ec;
  if (fs::is_directory(path, ec)) throw UsageError(option + " '" + path + "' is a folder; give a file name");
  const fs::path file(path);
  const fs::path folder = file.parent_path().empty() ? fs::path(".") : file.parent_path();
  if (fs::exists(folder, ec) && !fs::is_directory(folder, ec))
    throw UsageError(option + " '" + path + "': '" + folder.string() + "' is a file, not a folder");
  if (!fs::is_directory(folder, ec))
    throw UsageError(option + " '" + path + "': the folder '" + folder.string() + "' does not exist; create it first");
  // Create and remove a file there: permission bits alone miss read-only file systems, and root.
  const fs::path probe = folder / ("." + file.filename().string() + ".paco-write-check");
  const int fd = ::open(probe.c_str(), O_WRONLY | O_CREAT | O_EXCL, 0600);
  if (fd < 0 && errno != EEXIST)
    throw UsageError(option + " '" + path + "': cannot create files in the folder '" + folder.string() +
                     "': " + std::strerror(errno));
  if (fd >= 0) {
    ::close(fd);
    fs::remove(probe, ec);
  }
}

PendingOutput::PendingOutput(std::string final_path)
    : final_path_(std::move(final_path)), temp_path_(temporaryName(final_path_)) {
  checkOutputPath(final_path_, "output", {});
}

PendingOutput::~PendingOutput() {
  if (!committed_) {
    std::error_code ec;
    std::filesystem::remove(temp_path_, ec);
  }
}

void PendingOutput::commit() {
  std::error_code ec;
  std::filesystem::rename(temp_path_, final_path_, ec);
  if (ec)
    throw paco::IoError("cannot move '" + temp_path_ + "' to '" + final_path_ + "': " + ec.message());
  committed_ = true;
}

void StageTimer::start(const std::string& stage) {
  current_ = stage;
  started_ = std::chrono::steady_clock::now();
}

void StageTimer::stop() {
  if (current_.empty()) return;
  addStage(current_, std::chrono::duration<double>(std::chrono::steady_clock::now() - started_).count());
  current_.clear();
}

void StageTimer::addStage(const std::string& stage, double seconds) {
  const auto it = std::find_if(stages_.begin(), stages_.end(), [&](const auto& s) { return s.first == stage; });
  if (it == stages_.end()) stages_.emplace_back(stage, seconds);
  else it->second += seconds;
}

double StageTimer::total() const {
  double sum = 0;
  for (const auto& stage : stages_) sum += stage.second;
  return sum;
}

void StageTimer::add(const StageTimer& other) {
  for (const auto& [name, s] : other.stages_) addStage(name, s);
}

double StageTimer::seconds(const std::string& stage) const {
  for (const auto& [name, s] : stages_)
    if (name == stage) return s;
  return 0.0;
}

void StageTimer::print() const {
  std::printf("timing:\n");
  for (const auto& [name, s] : stages_) std::printf("  %-14s %8.3f s\n", name.c_str(), s);
  std::printf("  %-14s %8.3f s\n", "total", total());
}

}  // namespace paco::app
