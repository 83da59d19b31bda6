// The whole pipeline on shapes unlike MFCAD's cube-stock parts, as a user's scans might be: thin
// plates and slabs, sheet-metal profiles, stairs, a building scanned without its ground or its
// roof, a room scanned from inside. Each shape is sampled uniformly by area (normals left for the
// segmenter to estimate, as in an .xyz scan; the room also with its normals given, facing into it
// as a scanner inside gives them), run through `paco` as paco_reconstruct runs it (the shipped
// model or MODEL, four turns, fusion and the box fill), and scored against the true mesh. Prints a
// Markdown table (doc/results.md, twenty-ninth session).
// Usage: paco_shape_check [POINTS] [MODEL]   (POINTS default 8000)
#include "shapes.h"

#include <paco/common/error.h>
#include <paco/common/surface_mesh.h>
#include <paco/evaluation/methods.h>
#include <paco/evaluation/metrics.h>

#include <pcl/console/print.h>

#include <cmath>
#include <cstdio>
#include <exception>
#include <functional>
#include <string>
#include <vector>

namespace {

struct Shape {
  std::string name;
  paco::SurfaceMesh mesh;
  std::function<bool(const Eigen::Vector3d&, const Eigen::Vector3d&)> scanned;  // point, normal
  bool normals_facing_in = false;  // given, facing into the shape; else estimated
};

bool everywhere(const Eigen::Vector3d&, const Eigen::Vector3d&) { return true; }

std::vector<Shape> shapes() {
  using paco::test::makeBox;
  using paco::test::makePrism;
  std::vector<Shape> list;
  list.push_back({"box 2 x 1 x 0.7", makeBox({0, 0, 0}, {2, 1, 0.7}), everywhere});
  list.push_back({"plate 1 x 1 x 0.04", makeBox({0, 0, 0}, {1, 1, 0.04}), everywhere});
  list.push_back({"plate 1 x 1 x 0.04, its two sides only", makeBox({0, 0, 0}, {1, 1, 0.04}),
                  [](const Eigen::Vector3d&, const Eigen::Vector3d& n) { return std::abs(n.z()) > 0.5; }});
  list.push_back({"slab 10 x 10 x 0.5", makeBox({0, 0, 0}, {10, 10, 0.5}), everywhere});
  const auto bracket = [](double t) {
    return makePrism({{0, 0}, {1, 0}, {1, t}, {t, t}, {t, 0.8}, {0, 0.8}}, 1.0);
  };
  list.push_back({"sheet-metal L bracket, 0.05 thick", bracket(0.05), everywhere});
  list.push_back({"L bracket, 0.1 thick", bracket(0.1), everywhere});
  list.push_back({"four stairs", makePrism({{0, 0}, {1, 0}, {1, 0.25}, {0.75, 0.25}, {0.75, 0.5}, {0.5, 0.5},
                                            {0.5, 0.75}, {0.25, 0.75}, {0.25, 1}, {0, 1}},
                                           1.0),
                  everywhere});
  const auto building = [] { return makePrism({{0, 0}, {20, 0}, {20, 8}, {8, 8}, {8, 20}, {0, 20}}, 6.0); };
  list.push_back({"L-shaped building 20 x 20 x 6 m, no ground", building(),
                  [](const Eigen::Vector3d& p, const Eigen::Vector3d&) { return p.z() > 1e-6; }});
  list.push_back({"the same building, its walls only", building(),
                  [](const Eigen::Vector3d&, const Eigen::Vector3d& n) { return std::abs(n.z()) < 0.5; }});
  list.push_back({"sheet-metal U channel, 0.05 thick", paco::test::makeUChannel(1.0, 0.6, 0.05, 1.0), everywhere});
  list.push_back({"I-beam, flanges and web 0.05 thick",
                  makePrism({{0, 0}, {0.6, 0}, {0.6, 0.05}, {0.325, 0.05}, {0.325, 0.55}, {0.6, 0.55}, {0.6, 0.6},
                             {0, 0.6}, {0, 0.55}, {0.275, 0.55}, {0.275, 0.05}, {0, 0.05}},
                            1.0),
                  everywhere});
  list.push_back({"sheet-metal square tube 0.6 x 0.6, 0.05 thick", paco::test::makeSquareTube(0.6, 0.05, 1.0),
                  everywhere});
  const auto from_inside = [](const Eigen::Vector3d& p, const Eigen::Vector3d&) {
    return paco::test::seenFromInsideTheLShapedRoom(p);
  };
  list.push_back({"L-shaped room 6 x 7 x 2.6 m from inside, a wall and half the ceiling unseen",
                  paco::test::makeLShapedRoom(), from_inside});
  list.push_back({"the same room, its normals given (facing in)", paco::test::makeLShapedRoom(), from_inside, true});
  return list;
}

}  // namespace

int main(int argc, char** argv) {
  if (argc > 3) {
    std::fprintf(stderr, "usage: %s [POINTS] [MODEL]\n", argv[0]);
    return 2;
  }
  try {
    const std::size_t points = argc > 1 ? std::stoul(argv[1]) : 8000;
    if (points < 100) throw paco::InvalidInputError("POINTS must be at least 100");
    pcl::console::setVerbosityLevel(pcl::console::L_ERROR);
    std::printf("%zu points per shape, uniform by area, normals estimated unless given; `paco` with the %s model\n\n",
                points, argc > 2 ? argv[2] : "shipped");
    std::printf("| shape | assembler | result | faces | CD | HD (pred→true / true→pred) | volume / true |\n|---|---|---|---|---|---|---|\n");
    for (const Shape& shape : shapes()) {
      const paco::SurfaceSample sample = paco::sampleSurface(shape.mesh, points, 7);
      paco::evaluation::MethodInput in;
      for (std::size_t i = 0; i < sample.points.size(); ++i) {
        if (!shape.scanned(sample.points[i], sample.normals[i])) continue;
        pcl::PointNormal p;
        p.getVector3fMap() = sample.points[i].cast<float>();
        if (shape.normals_facing_in)
          p.getNormalVector3fMap() = -sample.normals[i].cast<float>();
        else
          p.normal_x = p.normal_y = p.normal_z = 0.0f;  // estimated, as for an .xyz scan
        in.input.push_back(p);
      }
      for (const std::string assembler : {"polyfit", "cell-complex"}) {
        paco::evaluation::MethodOptions options;
        options.assembler = assembler;
        options.time_limit = 10.0;
        if (argc > 2) options.model = argv[2];
        const paco::evaluation::MethodOutput out = paco::evaluation::runMethod("paco", in, options);
        std::printf("| %s | %s | ", shape.name.c_str(), assembler.c_str());
        if (!out.has_mesh || out.mesh.faces.empty()) {
          std::printf("failed: %s | | | | |\n", out.message.c_str());
          continue;
        }
        const paco::evaluation::MeshMetrics m = paco::evaluation::evaluateMesh(out.mesh, shape.mesh);
        std::printf("%s | %zu | %.2f | %.2f (%.2f / %.2f) | %.3f |\n", m.closed ? "closed" : "not closed", m.num_faces,
                    m.chamfer, m.hausdorff, m.hausdorff_pred_to_gt, m.hausdorff_gt_to_pred, m.volume_ratio);
      }
    }
  } catch (const std::exception& e) {
    std::fprintf(stderr, "error: %s\n", e.what());
    return 1;
  }
  return 0;
}
