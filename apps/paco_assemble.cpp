// paco_assemble: planar primitives -> watertight polygonal mesh (stage 4 of the pipeline).
//   paco_assemble planes.vg -o mesh.obj [--backend polyfit|cell-complex] [--solver cbc|glpk] ...
#include "app_support.h"

#include <paco/assembly/polygonal_assembler.h>
#include <paco/common/angles.h>
#include <paco/common/error.h>
#include <paco/common/progress.h>
#include <paco/io/cloud_io.h>
#include <paco/io/mesh_io.h>
#include <paco/io/vertex_groups_io.h>

#include <boost/program_options.hpp>

#include <cmath>
#include <cstdio>
#include <iostream>
#include <string>
#include <utility>
#include <vector>

namespace po = boost::program_options;

namespace {

const std::string kTool = "paco_assemble";

void printHelp(const po::options_description& options) {
  std::cout << "Usage: " << kTool << " PRIMITIVES -o MESH [options]\n\n"
            << "Assembles planar primitives into a closed, manifold, outward-oriented polygonal mesh.\n\n"
            << "PRIMITIVES  a PolyFit vertex-group file (.vg ascii, .bvg binary), or a labelled point cloud\n"
            << "            (.pcd/.ply/.xyz/.npy with a label / plane_id per point; label -1 = none).\n"
            << "MESH        output mesh, by extension: .obj, .off, .ply or .stl. Written only on success.\n\n"
            << options << "\n"
            << "Backends:\n"
            << "  polyfit       CGAL's PolyFit: intersect the planes into candidate faces and select a\n"
            << "                watertight subset by a binary program (CBC by default). Best quality.\n"
            << "  cell-complex  adaptive space partition by the planes + inside/outside min-cut. Fast.\n\n"
            << "Exit status: 0 on success; 1 when the reconstruction fails (too few planes, parallel\n"
            << "planes, solver failure or time-out, empty or non-watertight result); 2 for bad usage;\n"
            << "130 when interrupted (Ctrl-C).\n";
}

/// The planar primitives of an input file, in the working frame of its coordinate offset
/// (io::LabelledCloud::coordinate_offset), which the mesh must be moved back by.
struct InputPrimitives {
  std::vector<paco::PlanarPrimitive> primitives;
  Eigen::Vector3d coordinate_offset = Eigen::Vector3d::Zero();
};

InputPrimitives loadPrimitives(const std::string& path) {
  const std::string extension = paco::io::extensionOf(path);
  if (extension == ".vg" || extension == ".bvg") {
    const paco::io::VertexGroups groups = paco::io::loadVertexGroups(path);
    return {paco::io::toPrimitives(groups), groups.coordinate_offset};
  }
  paco::io::LabelledCloud cloud = paco::io::loadCloud(path);
  if (!cloud.hasLabels())
    throw paco::InvalidInputError("'" + path + "' has no per-point plane labels: segment it first with "
                                  "paco_segment, or give a .vg/.bvg file");
  return {paco::makePrimitives(cloud.points, paco::app::segmentationFromLabels(cloud, path)), cloud.coordinate_offset};
}

// The assembler's ranges, checked here to name the options and their units.
void validateAssemblyOptions(double time_limit, double fitting, double coverage, double complexity,
                             double smoothness, std::size_t min_support, double merge_angle_degrees,
                             double merge_distance) {
  using paco::app::shortNumber;
  using paco::app::UsageError;
  if (!(time_limit > 0.0)) throw UsageError("--time-limit must be more than 0 seconds, got " + shortNumber(time_limit));
  for (const auto& [option, weight] : {std::pair<const char*, double>{"--fitting", fitting},
                                       {"--coverage", coverage},
                                       {"--complexity", complexity}})
    if (!(weight >= 0.0 && std::isfinite(weight)))
      throw UsageError(std::string(option) + " must be a finite number >= 0, got " + shortNumber(weight));
  if (!(smoothness > 0.0 && std::isfinite(smoothness)))
    throw UsageError("--smoothness must be a finite number > 0, got " + shortNumber(smoothness));
  if (min_support < 3) throw UsageError("--min-support must be at least 3 (points of a plane), got " + std::to_string(min_support));
  if (!(merge_angle_degrees >= 0.0 && merge_angle_degrees < 90.0))
    throw UsageError("--merge-angle must be in [0, 90) degrees, got " + shortNumber(merge_angle_degrees));
  if (!(merge_distance >= 0.0 && merge_distance < 1.0))
    throw UsageError("--merge-distance must be in [0, 1) (a fraction of the diagonal), got " +
                     shortNumber(merge_distance));
}

int run(int argc, char** argv) {
  // The library's defaults, so that the help and the tool cannot drift from them.
  const paco::PolygonalAssembler defaults;
  std::string input, output;
  std::string backend = paco::toString(defaults.getBackend()), solver = paco::toString(defaults.getMipSolver());
  double time_limit = defaults.getTimeLimit(), fitting = defaults.getFittingWeight(),
         coverage = defaults.getCoverageWeight(), complexity = defaults.getComplexityWeight(),
         smoothness = defaults.getSmoothness();
  std::size_t min_support = defaults.getMinSupport(), max_candidate_faces = defaults.getMaxCandidateFaces();
  double merge_distance = defaults.getMergeDistance(), merge_angle = paco::radiansToDegrees(defaults.getMergeAngle());
  using paco::app::shortNumber;
  po::options_description options("Options");
  options.add_options()
      ("help,h", "print this help and exit")
      ("output,o", po::value(&output), "output mesh (.obj, .off, .ply, .stl)")
      ("backend,b", po::value(&backend)->default_value(backend), "polyfit | cell-complex")
      ("solver", po::value(&solver)->default_value(solver), "MIP solver of polyfit: cbc | glpk")
      ("time-limit", po::value(&time_limit)->default_value(time_limit, shortNumber(time_limit)),
       "time budget in seconds; polyfit keeps the best solution found by then")
      ("fitting", po::value(&fitting)->default_value(fitting, shortNumber(fitting)),
       "polyfit data-fitting weight (>= 0)")
      ("coverage", po::value(&coverage)->default_value(coverage, shortNumber(coverage)),
       "polyfit coverage weight (>= 0)")
      ("complexity", po::value(&complexity)->default_value(complexity, shortNumber(complexity)),
       "polyfit complexity weight (>= 0)")
      ("smoothness", po::value(&smoothness)->default_value(smoothness, shortNumber(smoothness)),
       "cell-complex area weight (> 0); halved, down to 1/64, when it leaves no solid")
      ("min-support", po::value(&min_support)->default_value(min_support), "drop primitives with fewer points (>= 3)")
      ("merge-angle", po::value(&merge_angle)->default_value(merge_angle, shortNumber(merge_angle)),
       "merge near-duplicate planes closer than this angle (degrees) ...")
      ("merge-distance", po::value(&merge_distance)->default_value(merge_distance, shortNumber(merge_distance)),
       "... and this mean point distance (fraction of the diagonal; 0: never merge)")
      ("max-candidate-faces", po::value(&max_candidate_faces)->default_value(max_candidate_faces),
       "polyfit: leave out the least confident primitives (confidence < 1) until the candidate faces fit (0: no limit)")
      ("no-warm-start", "polyfit: do not start the MIP solver from the cell complex's surface (a time-out then leaves no mesh)")
      ("keep-inward-normals", "keep normals that face the middle of the primitives' points as a whole (primitives "
       "of a room scanned from inside); by default every plane and normal is then turned outwards, so that the mesh "
       "is the solid they enclose (a room's volume)")
      ("verbose,v", "print the MIP solver's log");
  po::options_description hidden;
  hidden.add_options()("input", po::value(&input));
  po::options_description all;
  all.add(options).add(hidden);
  po::positional_options_description positional;
  positional.add("input", 1);
  const po::variables_map vm = paco::app::parseCommandLine(argc, argv, all, positional);
  if (vm.count("help")) {
    printHelp(options);
    return 0;
  }
  if (input.empty()) throw paco::app::UsageError("missing input file (PRIMITIVES)");
  if (output.empty()) throw paco::app::UsageError("missing output mesh (-o MESH)");
  paco::app::checkOutputPath(output, "-o", {".obj", ".off", ".ply", ".stl"});
  paco::app::checkOutputsAreNotInputs({{"PRIMITIVES", input}}, {{"-o", output}});
  validateAssemblyOptions(time_limit, fitting, coverage, complexity, smoothness, min_support, merge_angle,
                          merge_distance);

  paco::PolygonalAssembler assembler;
  paco::app::usageErrorIfInvalid([&] {
    assembler.setBackend(backend);
    assembler.setMipSolver(solver);
    assembler.setTimeLimit(time_limit);
    assembler.setFittingWeight(fitting);
    assembler.setCoverageWeight(coverage);
    assembler.setComplexityWeight(complexity);
    assembler.setSmoothness(smoothness);
    assembler.setMinSupport(min_support);
    assembler.setMergeAngle(paco::degreesToRadians(merge_angle));
    assembler.setMergeDistance(merge_distance);
    assembler.setMaxCandidateFaces(max_candidate_faces);
  });
  assembler.setVerbose(vm.count("verbose") > 0);
  assembler.setWarmStart(vm.count("no-warm-start") == 0);
  assembler.setTurnInwardNormals(vm.count("keep-inward-normals") == 0);

  paco::InterruptGuard interrupt_guard;
  paco::app::StageTimer timer;
  timer.start("load");
  InputPrimitives loaded = loadPrimitives(input);
  std::vector<paco::PlanarPrimitive>& primitives = loaded.primitives;
  timer.stop();
  if (primitives.empty())
    throw paco::InvalidInputError("'" + input + "' holds no primitives (no vertex group or labelled point); a closed "
                                  "mesh needs at least 4 planes");
  assembler.setInputPrimitives(std::move(primitives));
  std::printf("loaded %zu primitives from %s\n", assembler.getInputPrimitives().size(), input.c_str());
  paco::app::reportCoordinateOffset(loaded.coordinate_offset);

  timer.start("assemble");
  paco::SurfaceMesh mesh;
  const paco::AssemblyResult& result = assembler.reconstruct(mesh);
  timer.stop();
  if (result.num_merged || result.num_dropped)
    std::printf("pre-processing: %zu planes merged as near-duplicates, %zu dropped (too few points, or over the "
                "candidate-face budget)\n",
                result.num_merged, result.num_dropped);
  if (result.turned_inward_normals)
    std::printf("normals: %.0f %% of the primitives' points face their middle, as in a room scanned from inside; "
                "every plane and normal was turned outwards, so that the mesh is the solid they enclose "
                "(--keep-inward-normals keeps them)\n",
                100.0 * result.inward_normal_share);
  if (result.status == paco::AssemblyStatus::Interrupted) throw paco::InterruptedError(result.message);
  if (!result.ok())
    throw paco::Error("assembly failed (" + paco::toString(result.status) + "): " + result.message);
  if (assembler.getBackend() == paco::AssemblyBackend::PolyFit) {
    std::printf("polyfit: %zu candidate faces (%.3f s), MIP %zu variables x %zu constraints solved %s in %.3f s\n",
                result.num_candidate_faces, result.seconds_partition, result.num_variables, result.num_constraints,
                result.solution_is_optimal ? "to optimality" : "(not proven optimal)", result.seconds_solve);
    if (result.num_planes_separated)
      std::printf("polyfit: %zu plane shifts of 5e-5 of the diagonal, so that no four meet in a point and no three "
                  "share a line\n",
                  result.num_planes_separated);
    if (result.num_warm_start_faces)
      std::printf("polyfit: started from the cell complex's surface (%zu candidate faces; %zu around edges PolyFit "
                  "forbids left to the solver)\n",
                  result.num_warm_start_faces, result.num_warm_start_faces_released);
  } else {
    std::printf("cell-complex: %zu cells (%.3f s), %zu cell faces, labelling and mesh %.3f s\n", result.num_cells,
                result.seconds_partition, result.num_candidate_faces, result.seconds_solve);
  }
  if (!result.message.empty())
    std::printf("note: %s\n", result.message.c_str());
  else if (result.hit_time_limit)
    std::printf("note: the time limit was reached; the best solution found is used\n");

  timer.start("save");
  paco::app::PendingOutput pending(output);
  paco::app::moveToFileCoordinates(mesh, loaded.coordinate_offset);
  paco::io::saveMesh(pending.writePath(), mesh);
  pending.commit();
  timer.stop();

  std::printf("%s (%s%s): %zu planes used, %zu faces, %zu vertices, %s, volume %.6g\n", output.c_str(),
              paco::toString(assembler.getBackend()).c_str(),
              assembler.getBackend() == paco::AssemblyBackend::PolyFit
                  ? (std::string(", ") + paco::toString(assembler.getMipSolver())).c_str()
                  : "",
              result.num_planes_used, mesh.faces.size(), mesh.vertices.size(),
              result.topology.isClosedManifold() ? "closed" : "NOT closed", paco::signedVolume(mesh));
  timer.print();
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  return paco::app::runTool(kTool, [&] { return run(argc, argv); });
}
