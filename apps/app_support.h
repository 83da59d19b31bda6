#pragma once
// Shared plumbing of the paco_* tools: error reporting with a non-zero exit, timing, and output
// files that appear only when complete (never a partial file after an error or Ctrl-C).
#include <paco/common/error.h>

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <boost/program_options.hpp>

#include <chrono>
#include <functional>
#include <stdexcept>
#include <string>
#include <vector>

// Declared only: this header stays free of PCL, which paco_train must include after LibTorch.
namespace paco {
struct PlanarSegmentation;
struct SurfaceMesh;
namespace io {
struct LabelledCloud;
}
}  // namespace paco

namespace paco::app {

/// Runs a tool's body, with the allocator set to keep freed memory (paco::keepFreedMemoryForReuse);
/// turns paco::Error and std::exception into "<tool>: error: <message>" on
/// stderr and exit code 1 (2 for usage errors; 130 and "<tool>: interrupted; nothing written"
/// for paco::InterruptedError). Also removes the pending outputs on failure.
int runTool(const std::string& tool_name, const std::function<int()>& body);

/// Call only inside a catch block: prints the exception in flight as runTool does and returns
/// its exit code. A non-empty `subject` (paco_reconstruct's scan in a run of many) is named
/// before messages that do not come from paco, whose own messages name their file.
int reportCurrentException(const std::string& tool_name, const std::string& subject = std::string());

/// Ends the process with `code` after a tool's body has returned (its outputs committed or
/// removed), flushing stdout and stderr but skipping static destructors: at exit LibTorch
/// unregisters its thousands of operators one by one, about 0.3 s of a 1.7 s paco_reconstruct run
/// on the sample (doc/benchmarks.md, "Process start and exit"). Sanitizer builds exit normally, so that
/// LeakSanitizer's check at exit still runs. Only for a tool's main(), never inside runTool, which
/// tests call in-process.
[[noreturn]] void exitSkippingTeardown(int code);

/// Thrown for a bad command line; runTool prints it with a hint to use --help, exit code 2.
struct UsageError : std::runtime_error {
  using std::runtime_error::runtime_error;
};

/// Runs `work` (setting up a library object from the command line's values) and returns what it
/// returns; a paco::InvalidInputError from it, whose message names the bad value, becomes a
/// UsageError (exit 2, as for every other bad option), its message after `prefix` (e.g. the
/// option's name and ": ").
template <typename Work>
auto usageErrorIfInvalid(Work work, const std::string& prefix = "") {
  try {
    return work();
  } catch (const paco::InvalidInputError& e) {
    throw UsageError(prefix + e.what());
  }
}

/// Parses the command line with boost::program_options; a malformed command line (unknown
/// option, missing value, bad number, a negative number for an unsigned option) becomes a
/// UsageError, which runTool reports with exit 2.
boost::program_options::variables_map parseCommandLine(
    int argc, char** argv, const boost::program_options::options_description& options,
    const boost::program_options::positional_options_description& positional);

/// The value of a non-negative option that can also be "off" (infinity): "--clip-margin 0.1".
/// Anything else is a UsageError naming `option`.
double parseNonNegativeOrOff(const std::string& option, const std::string& text);

/// The most threads a --threads or --jobs option may ask for: 4 per hardware thread (256 when the
/// count is unknown).
unsigned maxThreads();

/// Throws a UsageError naming `option` unless `threads` is in [1, maxThreads()], or 0 when
/// `zero_meaning` is not empty (e.g. "one per core").
void validateThreads(const std::string& option, long long threads, const std::string& zero_meaning = "");

/// A file a tool reads or writes, and the option or argument that names it ("-o", "INPUT").
struct FileArgument {
  std::string option;
  std::string path;  ///< empty: not given, skipped
};

/// Throws a UsageError naming both options and paths when an output is the same file as an input
/// (also through a link, or as the "<stem>.partial<ext>" file PendingOutput writes first) or as
/// another output. Call it before any slow work: a tool must never replace its own input.
void checkOutputsAreNotInputs(const std::vector<FileArgument>& inputs, const std::vector<FileArgument>& outputs);

/// The segmentation that the per-point labels of `cloud` describe (paco_assemble and
/// paco_complete --use-labels): one segment per distinct label, whatever the numbers (negative:
/// no segment), numbered in order of first appearance, each with the plane fitted to its points
/// and oriented by their mean normal. Throws InvalidInputError naming `path` and the label when a
/// label has fewer than 3 points.
PlanarSegmentation segmentationFromLabels(const io::LabelledCloud& cloud, const std::string& path);

/// Prints where the working frame of a cloud read with a coordinate offset
/// (io::LabelledCloud::coordinate_offset) is, and that outputs go back to the file's
/// coordinates; nothing for a zero offset.
void reportCoordinateOffset(const Eigen::Vector3d& offset);
/// Warns on stderr when `path` is a .pcd written from a cloud with a non-zero coordinate offset:
/// PCD stores float32 positions (for PCL's point types), which round far coordinates.
void warnIfPcdRoundsFarCoordinates(const std::string& path, const Eigen::Vector3d& offset);
/// Moves a mesh made in the working frame of a cloud read with `offset` back to the file's
/// coordinates (SurfaceMesh stores doubles, so nothing is lost).
void moveToFileCoordinates(SurfaceMesh& mesh, const Eigen::Vector3d& offset);

/// How far `mesh` reaches beyond `box` (the scan's bounding box along `axes`, the columns of a
/// rotation: the box holds axesᵀ p of the scan's points p), as a fraction of the box's diagonal:
/// the largest distance from a vertex to the box (a face's farthest point is a vertex), 0 when
/// the mesh stays inside or the box is empty. Along the box fill's axes (fuseWithSeenFaces) the
/// fill's own closing box is the scan's, so only what the completion added past it counts.
double reachBeyondBox(const SurfaceMesh& mesh, const Eigen::AlignedBox3d& box,
                      const Eigen::Matrix3d& axes = Eigen::Matrix3d::Identity());

/// A note for a mesh that reaches more than kFarReach of the scan's diagonal beyond the scan's box
/// when the user said nothing of the scan (no --seen-from, --seen-from-point, --known-extent or
/// --extent-head): the network's guesses of the hidden side may reach where the object cannot be
/// (an airborne scan of a narrow building grew walls 8 m beside it), and only the user can bound
/// them. `reach` as reachBeyondBox gives it, `diagonal` in the input's units; "" below the bound.
std::string farReachNote(double reach, double diagonal);
inline constexpr double kFarReach = 0.2;

/// A number as --help shows a default: "0.7", not "0.69999999999999996".
std::string shortNumber(double value);

/// ", inlier distance raised to X of the diagonal: the scan is noisy" when noise adaptation
/// (PlanarSegmenter::setNoiseAdaptation) raised the segmenter's ε from `set` to `used`, else "".
std::string noisyScanNote(double set, double used);

/// " (N on a scan with noise)" when an exact scan lowered the segmenter's plane minimum from
/// `set` (N) to `used` (PlanarSegmenter::getUsedMinPointsPerPlane), else "".
std::string exactScanNote(int set, int used);

/// --noise-adaptation M (PlanarSegmenter::setNoiseAdaptation) of paco_reconstruct, paco_complete,
/// paco_eval and paco_segment (the default is the caller's), and its check: 0 (off) or a finite
/// positive number, else a UsageError.
void addNoiseAdaptationOption(boost::program_options::options_description& options, double& multiple);
void validateNoiseAdaptation(double multiple);

/// The observed-fusion options paco_reconstruct, paco_complete and paco_eval share, with the
/// same names and checks (paco::ObservedFusionOptions has their meaning). The defaults come from
/// the library (paco::app::libraryFusionFlags() in fusion_step.h, or
/// paco::evaluation::MethodOptions in paco_eval, which can be built without the completion
/// module), so that they are written once.
struct FusionFlags {
  FusionFlags(double align_unseen_degrees, double clip_margin, double tilt_margin, double fill_box_spacing,
              double unseen_point_fraction, double contradiction_radius, double join_distance);

  double align_unseen_degrees;
  std::string clip_margin;  ///< a number, or "off" (infinity)
  std::string tilt_margin;  ///< a number, or "off" (infinity)
  double fill_box_spacing;
  double unseen_point_fraction;
  double contradiction_radius;
  double join_distance;

  /// Adds --align-unseen, --clip-margin, --tilt-margin, --fill-box, --unseen-points,
  /// --contradiction-radius and --join-distance, bound to the fields above.
  void addTo(boost::program_options::options_description& options);
  /// Throws UsageError when a value is out of range.
  void validate() const;
  /// --clip-margin as a number (infinity for "off"); validates.
  double clipMargin() const;
  /// --tilt-margin as a number (infinity for "off"); validates.
  double tiltMargin() const;
};

/// Checks an output path before any slow work: its extension is one of `extensions` (lower case
/// with the dot; empty: any), it is not a folder, and its folder exists and takes a new file (one
/// is created and removed to tell). Throws a UsageError naming `option` ("-o", "--vg") and the
/// path otherwise.
void checkOutputPath(const std::string& path, const std::string& option, const std::vector<std::string>& extensions);

/// An output path that is written to "<path>.partial" first and renamed into place by commit().
/// The constructor checks the path (checkOutputPath, any extension).
/// Pending outputs that are never committed are deleted by runTool on failure and on destruction.
class PendingOutput {
 public:
  explicit PendingOutput(std::string final_path);
  ~PendingOutput();
  PendingOutput(const PendingOutput&) = delete;
  PendingOutput& operator=(const PendingOutput&) = delete;
  /// The path to write to now. It keeps the final extension (writers pick the format by it).
  const std::string& writePath() const { return temp_path_; }
  const std::string& finalPath() const { return final_path_; }
  void commit();

 private:
  std::string final_path_, temp_path_;
  bool committed_ = false;
};

/// Measures and prints per-stage wall times: "  segment      0.031 s". A stage timed twice prints
/// once with both times added.
class StageTimer {
 public:
  void start(const std::string& stage);
  void stop();
  double seconds(const std::string& stage) const;
  /// The sum of every stage's time.
  double total() const;
  /// Adds `other`'s stages to this timer's, by name (paco_reconstruct's total over many scans).
  void add(const StageTimer& other);
  void print() const;

 private:
  void addStage(const std::string& stage, double seconds);

  std::vector<std::pair<std::string, double>> stages_;
  std::string current_;
  std::chrono::steady_clock::time_point started_;
};

}  // namespace paco::app
