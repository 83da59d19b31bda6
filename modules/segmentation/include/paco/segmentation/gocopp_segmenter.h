#pragma once
// GoCoPP (Yu & Lafarge, CVPR 2022): region growing, then greedy local operators (merge, split,
// insert, exclude, transfer) that lower an energy of fidelity, simplicity and completeness.
// Usage:
//   paco::GoCoPPSegmenter<pcl::PointNormal> seg;           // the default backend
//   seg.setInputCloud(cloud); seg.setLambdaSimplicity(1.0);
//   paco::PlanarSegmentation result; seg.segment(result);
#include <paco/segmentation/planar_segmenter.h>

#include <pcl/point_cloud.h>
#include <pcl/point_types.h>

#include <Eigen/Core>

#include <cstddef>
#include <vector>

namespace paco {

/// Parameters of GoCoPP in the working frame (unit bounding-box diagonal).
struct GoCoPPParameters {
  double epsilon = 0.004;            ///< ε: inlier distance, fraction of the diagonal, > 0
  double normal_threshold = 0.85;    ///< τ: min |cos| between point and plane normals, [0, 1]
  int min_points = 50;               ///< σ: fewest points of a primitive, >= 3
  int neighbours = 20;               ///< k of the neighbourhood graph, >= 3
  double lambda_simplicity = 1.0;    ///< λs: weight of the number of primitives, [0, 3)
  double lambda_completeness = 1.0;  ///< λc: weight of the unassigned fraction, [0, 3 - λs)
  int max_rounds = 7;                ///< rounds of operators at most; stops earlier when one changes nothing
  /// Throws InvalidInputError naming the first parameter out of range.
  void validate() const;
};

/// The three terms of the GoCoPP energy U = (wf·fidelity + λs·simplicity + λc·completeness) / 3,
/// with wf = 3 - λs - λc: fidelity = mean |point-to-plane distance| of assigned points / ε,
/// simplicity = primitives / (N / σ), completeness = unassigned points / N.
struct GoCoPPEnergy {
  double fidelity = 0.0;
  double simplicity = 0.0;
  double completeness = 0.0;
  double total = 0.0;
};

/// The GoCoPP optimiser on a cloud with normals (any frame; ε is in the cloud's units). Not a
/// PCL-shaped class: GoCoPPSegmenter uses it, and tests and experiments drive its operators
/// one by one. Each try* operator applies its move only when it lowers the energy.
class GoCoPPOptimizer {
 public:
  /// `neighbours[i]`: the nearest neighbours of point i (self excluded). `points` and
  /// `neighbours` must outlive the optimiser. Throws InvalidInputError for bad parameters or
  /// mismatched sizes.
  GoCoPPOptimizer(const pcl::PointCloud<pcl::PointNormal>& points, const std::vector<std::vector<int>>& neighbours,
                  const GoCoPPParameters& parameters);

  /// Initial configuration: region growing from the flattest points (distance ε, normal τ),
  /// keeping regions of at least σ points.
  void growRegions();
  /// Any configuration: one label per point, -1 for unassigned. Labels with fewer than 3 points or
  /// no unique plane are dropped.
  void setLabels(const std::vector<int>& labels);

  /// Rounds of operators from a priority queue ordered by energy decrease, then transfer, until a
  /// round changes nothing or max_rounds. Returns the number of rounds run.
  int optimize();

  /// Merges two primitives sharing a neighbourhood edge into one plane (points farther than ε
  /// from it leave). Primitive ids are those of labels() at call time.
  bool tryMerge(int a, int b);
  /// Splits a primitive into two planes (two-plane clustering), each of at least σ points.
  bool trySplit(int a);
  /// Adds the unassigned neighbours of a primitive within ε of its plane and normal-compatible.
  bool tryInsert(int a);
  /// Removes the points of a primitive farther than ε from its plane (all of it if fewer than σ
  /// would remain).
  bool tryExclude(int a);
  /// Moves boundary points to a neighbouring primitive whose plane is within ε and agrees
  /// better with their normal. Kept only when the energy drops.
  bool transfer();

  /// Compact labels (0 .. numPrimitives()-1, -1 for unassigned). Ids change after merges and
  /// exclusions of whole primitives.
  std::vector<int> labels() const;
  std::size_t numPrimitives() const;
  GoCoPPEnergy energy() const;

 private:
  struct Primitive {
    std::vector<int> members;
    Eigen::Vector3d normal = Eigen::Vector3d::UnitZ();
    double offset = 0.0;
    double distance_sum = 0.0;
    int version = 0;
    bool alive = false;
  };
  /// A proposed new state of some primitives, evaluated but not applied.
  struct Proposal {
    enum class Kind { Merge, Split, Insert, Exclude } kind = Kind::Merge;
    int a = -1, b = -1;
    std::vector<std::vector<int>> groups;  ///< new member lists (1 or 2; 0 removes `a`)
    std::vector<Eigen::Vector3d> normals;
    std::vector<double> offsets, distance_sums;
    double delta_distance = 0.0;
    long delta_assigned = 0;
    int delta_primitives = 0;
    /// Appends one new primitive: its members, plane and sum of point-to-plane distances.
    void addGroup(std::vector<int> members, const Eigen::Vector3d& normal, double offset, double distance_sum) {
      groups.push_back(std::move(members));
      normals.push_back(normal);
      offsets.push_back(offset);
      distance_sums.push_back(distance_sum);
    }
  };

  double energyOf(double distance_sum, double assigned, double primitives) const;
  double deltaEnergy(const Proposal& p) const;
  bool fit(const std::vector<int>& members, Eigen::Vector3d& normal, double& offset) const;
  double distance(int point, const Eigen::Vector3d& normal, double offset) const;
  double distanceSum(const std::vector<int>& members, const Eigen::Vector3d& normal, double offset) const;
  int addPrimitive(std::vector<int> members);
  int resolve(int id) const;
  int idOfCompact(int compact) const;

  bool proposeMerge(int a, int b, Proposal& p) const;
  bool proposeSplit(int a, Proposal& p) const;
  bool proposeInsert(int a, Proposal& p) const;
  bool proposeExclude(int a, Proposal& p) const;
  bool propose(Proposal::Kind kind, int a, int b, Proposal& p) const;
  void apply(const Proposal& p);
  bool tryOperator(Proposal::Kind kind, int a, int b);
  bool runRound();

  const pcl::PointCloud<pcl::PointNormal>& points_;
  const std::vector<std::vector<int>>& neighbours_;
  GoCoPPParameters parameters_;
  std::vector<int> label_;               ///< primitive id per point, -1 unassigned
  std::vector<Primitive> primitives_;
  std::vector<int> merged_into_;         ///< forwarding of ids merged away, -1 otherwise
  double total_distance_ = 0.0;
  long assigned_ = 0;
  long alive_ = 0;
};

/// The default backend: our implementation of GoCoPP. ε, τ, σ and k come from the base class.
template <typename PointT>
class GoCoPPSegmenter : public PlanarSegmenter<PointT> {
 public:
  using Ptr = std::shared_ptr<GoCoPPSegmenter<PointT>>;
  std::string name() const override { return "gocopp"; }

  /// λs, the weight of simplicity (fewer primitives). Range [0, 3); default 1.
  void setLambdaSimplicity(double lambda);
  double getLambdaSimplicity() const { return lambda_simplicity_; }
  /// λc, the weight of completeness (fewer unassigned points). Range [0, 3); default 1.
  /// λs + λc must stay below 3 (the fidelity weight is 3 - λs - λc).
  void setLambdaCompleteness(double lambda);
  double getLambdaCompleteness() const { return lambda_completeness_; }
  /// Rounds of operators at most. Range >= 0 (0: region growing only); default 7.
  void setMaxRounds(int rounds);
  int getMaxRounds() const { return max_rounds_; }

  /// The energy terms of the last segment() call, before and after the operators.
  GoCoPPEnergy initialEnergy() const { return initial_energy_; }
  GoCoPPEnergy finalEnergy() const { return final_energy_; }

 protected:
  void performSegmentation(std::vector<int>& labels) override;

  double lambda_simplicity_ = 1.0;
  double lambda_completeness_ = 1.0;
  int max_rounds_ = 7;
  GoCoPPEnergy initial_energy_, final_energy_;
};

extern template class GoCoPPSegmenter<pcl::PointXYZ>;
extern template class GoCoPPSegmenter<pcl::PointNormal>;

}  // namespace paco
