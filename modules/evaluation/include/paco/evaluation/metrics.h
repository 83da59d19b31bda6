#pragma once
// Usage:
//   paco::evaluation::MeshMetrics m = paco::evaluation::evaluateMesh(predicted, ground_truth);
//   std::cout << "CD=" << m.chamfer << " HD=" << m.hausdorff << " NC=" << m.normal_consistency;
//   paco::evaluation::MeshMetrics f = paco::evaluation::evaluateFailure(ground_truth);  // the box score
#include <paco/common/plane.h>
#include <paco/common/surface_mesh.h>

#include <cstddef>
#include <cstdint>
#include <limits>
#include <string>
#include <vector>

namespace paco::evaluation {

/// How meshes are compared; the defaults are the paper's protocol.
struct MetricOptions {
  /// Points sampled uniformly by area on each mesh (default 10,000, as in the paper; >= 1).
  std::size_t num_samples = 10000;
  /// Seed of the samples on the predicted mesh. Default 1.
  std::uint64_t prediction_seed = 1;
  /// Seed of the samples on the ground-truth mesh. Default 2: independent of the prediction's, as
  /// in the reference code, so a perfect mesh scores the sampling floor, not 0. Give both the
  /// same seed to get exactly CD = HD = 0 and NC = 1 for a mesh compared with itself.
  std::uint64_t reference_seed = 2;
  /// Move both meshes into the ground truth's normalised frame (centre of its bounding box at the
  /// origin, bounding-box diagonal 1) before measuring. Default true; a no-op for meshes that are
  /// already in that frame (dataset samples).
  bool normalize_by_reference = true;
  /// Factor applied to CD and HD (default 100: the paper's tables show CD and HD x 100).
  double distance_scale = 100.0;
  /// With seen points (the evaluateMesh overload that takes them): GT surface within this
  /// distance of a seen point counts as seen, the rest as hidden. In the frame CD is measured in
  /// (the GT's normalised frame unless normalize_by_reference is false). Default 0.03: about
  /// twice the spacing of a 2,048-point scan of a part of unit diagonal, so the gaps between
  /// scan points count as seen. > 0.
  double seen_radius = 0.03;
};

/// CD, HD and NC between two sampled surfaces, in the units of the samples (no scaling).
struct SurfaceDistances {
  double chamfer = 0.0;             ///< mean NN distance pred->GT plus mean NN distance GT->pred
  double chamfer_pred_to_gt = 0.0;  ///< mean NN distance pred->GT: surface the prediction has where the GT has none
  double chamfer_gt_to_pred = 0.0;  ///< mean NN distance GT->pred: GT surface the prediction misses
  double hausdorff = 0.0;           ///< max of the two directed Hausdorff distances
  double hausdorff_pred_to_gt = 0.0, hausdorff_gt_to_pred = 0.0;  ///< the directed Hausdorff distances
  double normal_consistency = 1.0;  ///< mean |n_pred . n_gt| at nearest neighbours, both directions averaged
  /// The two directions of NC: the prediction's samples against their nearest GT sample (a
  /// stray or tilted face) and the GT's against their nearest predicted sample (a missed one).
  double normal_consistency_pred_to_gt = 1.0, normal_consistency_gt_to_pred = 1.0;
};

/// Nearest neighbours come from a kd-tree (FLANN through pcl::KdTreeFLANN). Throws
/// InvalidInputError when either sample is empty or the normals do not match the points.
SurfaceDistances compareSamples(const SurfaceSample& predicted, const SurfaceSample& reference);

/// Everything measured on one predicted mesh against its ground truth.
struct MeshMetrics {
  double chamfer = 0.0;             ///< CD, x distance_scale, in the GT's normalised frame
  /// The two halves of CD (x distance_scale): they tell extra surface (pred->GT) from missed
  /// surface (GT->pred), which CD alone does not.
  double chamfer_pred_to_gt = 0.0, chamfer_gt_to_pred = 0.0;
  double hausdorff = 0.0;           ///< HD, x distance_scale, in the GT's normalised frame
  /// The two directed Hausdorff distances (x distance_scale); HD is the larger. They tell a
  /// stray face (pred->GT) from a missed feature (GT->pred).
  double hausdorff_pred_to_gt = 0.0, hausdorff_gt_to_pred = 0.0;
  double normal_consistency = 0.0;  ///< NC in [0, 1]
  /// The two directions NC averages (see SurfaceDistances).
  double normal_consistency_pred_to_gt = 0.0, normal_consistency_gt_to_pred = 0.0;
  std::size_t num_faces = 0;        ///< polygon faces of the prediction (#f)
  std::size_t num_vertices = 0;     ///< vertices of the prediction (#v)
  bool closed = false;              ///< the prediction is closed, manifold and consistently oriented
  /// Volume of the prediction / volume of the GT; NaN unless the prediction is a closed solid.
  double volume_ratio = 0.0;
  /// Measured only when the seen points (the partial input) are given, NaN otherwise. The share
  /// of the GT surface that is hidden (farther than MetricOptions::seen_radius from every seen
  /// point), and GT->pred (x distance_scale) over the seen and over the hidden GT surface:
  /// chamfer_gt_to_pred = (1 - hidden_fraction) * ..._seen + hidden_fraction * ..._hidden. The
  /// hidden half is what completion has to recover; a part of the GT that is all seen or all
  /// hidden has NaN for the empty half. NC's GT->pred direction is split the same way.
  double hidden_fraction = std::numeric_limits<double>::quiet_NaN();
  double chamfer_gt_to_pred_seen = std::numeric_limits<double>::quiet_NaN();
  double chamfer_gt_to_pred_hidden = std::numeric_limits<double>::quiet_NaN();
  double normal_consistency_gt_to_pred_seen = std::numeric_limits<double>::quiet_NaN();
  double normal_consistency_gt_to_pred_hidden = std::numeric_limits<double>::quiet_NaN();
};

/// CD, HD, NC, #f, #v, closedness and volume ratio of `predicted` against `reference` (the GT).
/// Throws InvalidInputError when either mesh is invalid or has no area.
MeshMetrics evaluateMesh(const SurfaceMesh& predicted, const SurfaceMesh& reference,
                         const MetricOptions& options = {});

/// The same, and GT->pred split into the GT surface the scan saw and the surface it did not:
/// `seen_points` are the partial input's points, in the reference's frame (as given, before any
/// normalisation). No seen points means every GT sample is hidden. Throws InvalidInputError for
/// a non-finite seen point or seen_radius <= 0.
MeshMetrics evaluateMesh(const SurfaceMesh& predicted, const SurfaceMesh& reference,
                         const std::vector<Eigen::Vector3d>& seen_points, const MetricOptions& options = {});

/// Which box a failed reconstruction is scored as.
enum class FailureBox {
  /// The axis-aligned bounding box of the GT mesh, in the GT's normalised frame: its diagonal is
  /// 1 and its centre the origin (the paper's "normalized bounding box", Table S1). Default.
  ReferenceBoundingBox,
  /// A cube of diagonal 1 (edge 1/sqrt(3)) centred at the GT's bounding-box centre: the paper's
  /// main text says "the unit cube". Equal to the default for cube-like parts.
  UnitDiagonalCube,
};

/// The closed box mesh (6 quads, outward) a failure is scored as, in the reference's own frame
/// (scaled back from the normalised frame, so evaluateMesh(failureBox(gt), gt) is the failure score).
SurfaceMesh failureBox(const SurfaceMesh& reference, FailureBox box = FailureBox::ReferenceBoundingBox);

/// The score of a failed case: evaluateMesh(failureBox(reference, box), reference, options), with
/// #f = #v = 0 and closed = false (nothing was produced).
MeshMetrics evaluateFailure(const SurfaceMesh& reference, const MetricOptions& options = {},
                            FailureBox box = FailureBox::ReferenceBoundingBox);
/// The same with GT->pred split by `seen_points`, as the evaluateMesh overload that takes them.
MeshMetrics evaluateFailure(const SurfaceMesh& reference, const std::vector<Eigen::Vector3d>& seen_points,
                            const MetricOptions& options = {}, FailureBox box = FailureBox::ReferenceBoundingBox);

/// Agreement of predicted planes with the GT planes (supplementary Sec. "Evaluation on Primitive
/// Parameters"): a minimum-cost one-to-one matching (Hungarian) on 1 - |cos| of the normals.
struct PrimitiveAgreement {
  /// Sum of |cos| over matched pairs / number of GT planes: unmatched GT planes count as 0.
  /// 0 when there are no predicted planes; NaN when there are no GT planes.
  double nc_prim = 0.0;
  std::size_t matched = 0;              ///< pairs formed: min(#pred, #GT)
  std::size_t unmatched_predicted = 0;  ///< predicted planes left without a GT partner
  std::size_t unmatched_reference = 0;  ///< GT planes left without a predicted partner
  std::vector<int> reference_of_predicted;  ///< per predicted plane: its GT plane, or -1
};

PrimitiveAgreement comparePrimitives(const std::vector<Plane>& predicted, const std::vector<Plane>& reference);

}  // namespace paco::evaluation
