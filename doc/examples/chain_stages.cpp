// Chaining the four paco stages by hand, the way PCL users chain filters.
//
//   chain_stages INPUT.pcd OUTPUT.obj [MODEL.pt]
//
// Each stage is set up with setters, given its input, and run with one verb. Swapping a backend
// is one call: the segmenter by name in makePlanarSegmenter(), the assembler with setBackend().
#include <torch/torch.h>  // LibTorch first: Qt's `slots` macro (pulled in by some PCL headers) breaks it

#include <paco/assembly/polygonal_assembler.h>
#include <paco/common/error.h>
#include <paco/completion/observed_fusion.h>
#include <paco/completion/parametric_completer.h>
#include <paco/encoding/completion_model.h>
#include <paco/encoding/plane_proxy_encoder.h>
#include <paco/io/cloud_io.h>
#include <paco/io/mesh_io.h>
#include <paco/common/normal_sides.h>
#include <paco/segmentation/planar_segmenter.h>

#include <iostream>

int main(int argc, char** argv) {
  if (argc < 3) {
    std::cerr << "usage: chain_stages INPUT.pcd OUTPUT.obj [MODEL.pt]\n";
    return 2;
  }
  try {
    // Any cloud, any units: .pcd, .ply, .xyz or .npy, with or without normals. Coordinates far from
    // 0 for the object's size (UTM, national grids) come relative to scan.coordinate_offset.
    const paco::io::LabelledCloud scan = paco::io::loadCloud(argv[1]);
    auto cloud = std::make_shared<pcl::PointCloud<pcl::PointNormal>>(scan.points);
    // Normals that face the scan's middle as a whole (a room scanned from inside) turned outwards,
    // as paco_reconstruct does: the network was trained on normals facing out of the solid. (The
    // assembler would turn such primitives itself, but the completion before it would not.)
    paco::turnInwardNormalsOutward(*cloud);

    // Stage 1: planar segmentation. Other backends: "region-growing", "ransac", "efficient-ransac".
    auto segmenter = paco::makePlanarSegmenter<pcl::PointNormal>("gocopp");
    segmenter->setInputCloud(cloud);
    segmenter->setDistanceThreshold(0.004);  // fraction of the bounding-box diagonal
    // paco_reconstruct's plane minimums (1 % of the points; 0.25 % on an exact scan; 0.15 % for a
    // plane parallel to a larger one) and its widening of the inlier distance on a noisy scan.
    paco::setScanDefaults(*segmenter, cloud->size(), 0, 0);
    paco::PlanarSegmentation segmentation;
    segmenter->segment(segmentation);
    std::cout << "segments: " << segmentation.size() << "\n";

    // Stages 2 and 3: the learned completion, when a model is at hand.
    std::vector<paco::PlanarPrimitive> primitives;
    const std::string model_path = argc > 3 ? argv[3] : paco::CompletionModel::findShippedModel();
    if (!model_path.empty()) {
      auto model = paco::CompletionModel::load(model_path);
      paco::PlaneProxyEncoder encoder;
      encoder.setModel(model);
      encoder.setInputCloud(cloud);
      encoder.setSegmentation(segmentation);
      paco::PlaneProxies proxies;
      encoder.encode(proxies);

      paco::ParametricCompleter completer;
      completer.setModel(model);
      completer.setConfidenceThreshold(0.7);
      completer.setInputProxies(proxies);
      completer.complete(primitives);  // in the input's own frame and units
      // paco_reconstruct runs stages 2-3 on four turns of the scan and keeps the planes most turns
      // predict: paco::completeWithTurns(model, cloud, segmentation, {}) (turn_ensemble.h).
      // Seen faces keep their fitted planes and points; the network supplies the unseen ones.
      primitives = paco::fuseWithObserved(std::move(primitives), paco::makePrimitives(*cloud, segmentation));
    } else {
      primitives = paco::makePrimitives(*cloud, segmentation);  // no model: the direct baseline
    }
    std::cout << "primitives: " << primitives.size() << "\n";

    // Stage 4: polygonal assembly. Swap to the graph-cut backend with setBackend("cell-complex").
    paco::PolygonalAssembler assembler;
    assembler.setBackend("polyfit");
    assembler.setMipSolver("cbc");
    assembler.setInputPrimitives(primitives);
    // paco::SurfaceMesh holds double vertices; reconstruct(pcl::PolygonMesh&) gives PCL's float32 mesh.
    paco::SurfaceMesh mesh;
    const paco::AssemblyResult& result = assembler.reconstruct(mesh);
    if (!result.ok()) {
      std::cerr << "assembly failed: " << paco::toString(result.status) << ": " << result.message << "\n";
      return 1;
    }
    for (Eigen::Vector3d& v : mesh.vertices) v += scan.coordinate_offset;  // back to the file's coordinates
    paco::io::saveMesh(argv[2], mesh);
    std::cout << "mesh: " << mesh.faces.size() << " faces -> " << argv[2] << "\n";
    return 0;
  } catch (const paco::Error& e) {
    std::cerr << "error: " << e.what() << "\n";
    return 1;
  }
}
