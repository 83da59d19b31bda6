// Benchmark of paco::PolygonalAssembler (not a test): time and quality of both backends and both
// MIP solvers on exact primitives of generated parts with 10-40 planes, and optionally on the
// ground-truth planes of MFCAD parts. Prints Markdown tables (pasted into doc/assembly.md).
//   bench_assembly [--glpk-time-limit 10] [--mfcad DIR --mfcad-count 60]
#include <paco/assembly/polygonal_assembler.h>
#include <paco/evaluation/metrics.h>
#include <paco/io/mesh_io.h>
#include <paco/io/vertex_groups_io.h>

#include "shape_primitives.h"
#include "shapes.h"
#include <paco/common/angles.h>

#include <boost/program_options.hpp>

#include <Eigen/Geometry>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <ctime>

#include <sys/resource.h>
#include <filesystem>
#include <random>
#include <string>
#include <vector>

namespace {

struct Config {
  std::string label, backend, solver;
  double time_limit;
};

struct Outcome {
  bool ok = false, closed = false, timed_out = false;
  double seconds = 0, cpu_seconds = 0, volume_error = 0;
  double chamfer = -1;  ///< CD x 100 to the true mesh (-1: no mesh)
  std::size_t planar_faces = 0, planes_used = 0;
  std::string status;
};

std::string formatChamfer(double chamfer) {
  if (chamfer < 0) return "-";
  char text[32];
  std::snprintf(text, sizeof(text), "%.2f", chamfer);
  return text;
}

// CPU seconds of this process and its waited-for children (the MIP solver runs in a child).
double cpuSeconds() {
  double total = 0.0;
  for (int who : {RUSAGE_SELF, RUSAGE_CHILDREN}) {
    rusage usage{};
    getrusage(who, &usage);
    total += usage.ru_utime.tv_sec + usage.ru_stime.tv_sec + 1e-6 * (usage.ru_utime.tv_usec + usage.ru_stime.tv_usec);
  }
  return total;
}

// Quality against the true surface: the evaluation's CD (x 100, unit-diagonal frame).
double chamferToTruth(const paco::SurfaceMesh& mesh, const paco::SurfaceMesh& truth) {
  return paco::evaluation::evaluateMesh(mesh, truth).chamfer;
}

Outcome runOnce(const std::vector<paco::PlanarPrimitive>& primitives, const paco::SurfaceMesh& truth,
                double true_volume, const Config& config) {
  paco::PolygonalAssembler assembler;
  assembler.setInputPrimitives(primitives);
  assembler.setBackend(config.backend);
  assembler.setMipSolver(config.solver);
  assembler.setTimeLimit(config.time_limit);
  assembler.setMergeDistance(0.0);  // exact primitives: distinct planes stay distinct
  paco::SurfaceMesh mesh;
  const double cpu_start = cpuSeconds();
  const auto& result = assembler.reconstruct(mesh);
  const double cpu = cpuSeconds() - cpu_start;
  Outcome outcome;
  outcome.ok = result.ok();
  outcome.seconds = result.seconds;
  outcome.cpu_seconds = cpu;
  outcome.status = paco::toString(result.status);
  outcome.timed_out = result.hit_time_limit || result.status == paco::AssemblyStatus::TimeLimit;
  outcome.planes_used = result.num_planes_used;
  if (!mesh.empty()) {
    outcome.closed = paco::analyseTopology(mesh).isClosedManifold();
    outcome.volume_error = std::abs(paco::signedVolume(mesh) - true_volume) / true_volume;
    outcome.planar_faces = paco::test::countPlanarRegions(mesh);
    outcome.chamfer = chamferToTruth(mesh, truth);
  }
  return outcome;
}

// A staircase profile with k steps, extruded: 2k + 4 planes, all axis-aligned before rotation.
paco::SurfaceMesh makeStairs(int steps) {
  std::vector<Eigen::Vector2d> profile = {{0, 0}, {steps * 0.1, 0}};
  for (int i = 1; i <= steps; ++i) {
    profile.emplace_back((steps - i + 1) * 0.1, i * 0.07);
    profile.emplace_back((steps - i) * 0.1, i * 0.07);
  }
  return paco::test::makePrism(profile, 0.5);
}

// A star-shaped prism with n sides (n + 2 planes), walls at many angles.
paco::SurfaceMesh makeStar(int sides, unsigned seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> jitter(-0.15, 0.15);
  std::vector<Eigen::Vector2d> profile;
  for (int i = 0; i < sides; ++i) {
    const double angle = 2 * paco::kPi * (i + 0.3 * jitter(rng)) / sides;
    const double radius = (i % 2 ? 0.65 : 1.0) + jitter(rng);
    profile.emplace_back(radius * std::cos(angle), radius * std::sin(angle));
  }
  return paco::test::makePrism(profile, 0.8);
}

Eigen::Matrix3d someRotation() {
  return (Eigen::AngleAxisd(0.61, Eigen::Vector3d(0.3, 1, 0.2).normalized()) *
          Eigen::AngleAxisd(0.23, Eigen::Vector3d::UnitX()))
      .toRotationMatrix();
}

double percentile(std::vector<double> v, double q) {
  if (v.empty()) return 0;
  std::sort(v.begin(), v.end());
  return v[std::min(v.size() - 1, static_cast<std::size_t>(q * (v.size() - 1) + 0.5))];
}

}  // namespace

int main(int argc, char** argv) {
  namespace po = boost::program_options;
  double glpk_time_limit = 10, time_limit = 60;
  std::string mfcad, only, save_primitives;
  std::size_t mfcad_count = 60;
  po::options_description options("bench_assembly options");
  options.add_options()("help,h", "help")("glpk-time-limit", po::value(&glpk_time_limit), "seconds for GLPK (10)")(
      "time-limit", po::value(&time_limit), "seconds for CBC and cell-complex (60)")(
      "mfcad", po::value(&mfcad), "folder of MFCAD .obj parts (optional)")(
      "mfcad-count", po::value(&mfcad_count), "number of parts, evenly spaced in name order (60)")(
      "only", po::value(&only), "run only the MFCAD parts whose name contains this")(
      "save-primitives", po::value(&save_primitives), "write each MFCAD part's primitives as DIR/<name>.bvg");
  po::variables_map vm;
  po::store(po::parse_command_line(argc, argv, options), vm);
  po::notify(vm);
  if (vm.count("help")) {
    std::printf("%s\n", "bench_assembly [--glpk-time-limit S] [--time-limit S] [--mfcad DIR --mfcad-count N]");
    return 0;
  }

  const std::vector<Config> configs = {{"polyfit+cbc", "polyfit", "cbc", time_limit},
                                       {"polyfit+glpk", "polyfit", "glpk", glpk_time_limit},
                                       {"cell-complex", "cell-complex", "cbc", time_limit}};

  std::printf("## Generated parts (exact primitives, 8000 points)\n\n");
  std::printf("| part | planes | backend | wall (s) | CPU (s) | status | closed | volume error | planar faces | CD to truth |\n");
  std::printf("|---|---:|---|---:|---:|---|---|---:|---:|---:|\n");
  for (int planes : {10, 20, 30, 40}) {
    struct Part {
      std::string name;
      paco::SurfaceMesh mesh;
    };
    std::vector<Part> parts = {{"stairs", makeStairs((planes - 4) / 2)}, {"star", makeStar(planes - 2, 7u + planes)}};
    for (auto& part : parts) {
      paco::test::transformMesh(part.mesh, someRotation(), Eigen::Vector3d(3, -2, 1));
      const auto primitives = paco::test::primitivesOf(part.mesh, 8000);
      const double volume = paco::signedVolume(part.mesh);
      for (const auto& config : configs) {
        const Outcome o = runOnce(primitives, part.mesh, volume, config);
        std::printf("| %s | %zu | %s | %.3f | %.3f | %s%s | %s | %.2f %% | %zu | %s |\n", part.name.c_str(),
                    primitives.size(), config.label.c_str(), o.seconds, o.cpu_seconds, o.status.c_str(), o.timed_out ? " (time limit)" : "",
                    o.closed ? "yes" : "no", 100 * o.volume_error, o.planar_faces, formatChamfer(o.chamfer).c_str());
        std::fflush(stdout);
      }
    }
  }

  // Floors and walls of a building: planes that cross the whole box make the largest complexes.
  std::printf("\n## Lattices of covered planes (the unit cube and k planes per axis, 150 points each)\n\n");
  std::printf("| k | seed | planes | cells | cell-complex wall (s) | status | closed | relabelling flips |\n");
  std::printf("|---:|---:|---:|---:|---:|---|---|---:|\n");
  for (int inner : {4, 6, 8, 10})
    for (unsigned seed : {1u, 2u, 3u}) {
      paco::PolygonalAssembler assembler;
      assembler.setInputPrimitives(paco::test::latticeOfCoveredPlanes(inner, seed));
      assembler.setBackend("cell-complex");
      assembler.setTimeLimit(time_limit);
      paco::SurfaceMesh mesh;
      const auto& result = assembler.reconstruct(mesh);
      std::printf("| %d | %u | %zu | %zu | %.3f | %s | %s | %d |\n", inner, seed, result.num_input_planes, result.num_cells,
                  result.seconds, paco::toString(result.status).c_str(),
                  !mesh.empty() && paco::analyseTopology(mesh).isClosedManifold() ? "yes" : "no",
                  result.num_crossings_resolved);
      std::fflush(stdout);
    }

  // PolyFit with a tight budget on the same lattices: CBC rarely solves them in time, so what
  // counts is that the warm start's surface comes back, and how far past the budget.
  constexpr double kTightBudget = 2.0;
  std::printf("\n## PolyFit + CBC with a %.0f s budget on the same lattices (every candidate face)\n\n", kTightBudget);
  std::printf("| k | seed | candidate faces | wall (s) | status | warm start returned | closed |\n");
  std::printf("|---:|---:|---:|---:|---|---|---|\n");
  for (int inner : {6, 8, 10})
    for (unsigned seed : {1u, 2u, 3u}) {
      paco::PolygonalAssembler assembler;
      assembler.setInputPrimitives(paco::test::latticeOfCoveredPlanes(inner, seed));
      assembler.setMaxCandidateFaces(0);
      assembler.setTimeLimit(kTightBudget);
      paco::SurfaceMesh mesh;
      const auto& result = assembler.reconstruct(mesh);
      std::printf("| %d | %u | %zu | %.3f | %s | %s | %s |\n", inner, seed, result.num_candidate_faces, result.seconds,
                  paco::toString(result.status).c_str(), result.returned_warm_start ? "yes" : "no",
                  !mesh.empty() && paco::analyseTopology(mesh).isClosedManifold() ? "yes" : "no");
      std::fflush(stdout);
    }

  if (mfcad.empty() || !std::filesystem::is_directory(mfcad)) return 0;
  std::vector<std::filesystem::path> files;
  for (const auto& entry : std::filesystem::directory_iterator(mfcad))
    if (entry.path().extension() == ".obj") files.push_back(entry.path());
  std::sort(files.begin(), files.end());
  std::vector<std::filesystem::path> chosen;
  for (std::size_t i = 0; i < mfcad_count && !files.empty(); ++i)
    chosen.push_back(files[i * files.size() / mfcad_count]);

  std::printf("\n## MFCAD parts (ground-truth planes, 10000 points)\n\n");
  std::printf("| part | planes | polyfit+cbc wall / CPU (s) | closed | vol. err | CD | cell-complex wall / CPU (s) | closed | vol. err | CD |\n");
  std::printf("|---|---:|---:|---|---:|---:|---:|---|---:|---:|\n");
  const std::vector<Config> mfcad_configs = {configs[0], configs[2]};
  std::vector<std::vector<double>> times(2), cpu_times(2), chamfers(2);
  std::size_t runs = 0;
  std::vector<std::size_t> closed(2, 0), under_goal(2, 0), good_volume(2, 0);
  const double goals[2] = {10.0, 1.0};
  for (const auto& file : chosen) {
    if (!only.empty() && file.stem().string().find(only) == std::string::npos) continue;
    ++runs;
    const paco::SurfaceMesh mesh = paco::io::loadMesh(file.string());
    // Coplanar triangles grouped as in mfcad.tsv: normals within ~0.06 deg, offsets 5e-4 of the diagonal.
    const auto primitives = paco::test::primitivesOf(mesh, 10000, std::cos(paco::degreesToRadians(0.06)), 5e-4);
    const double volume = std::abs(paco::signedVolume(mesh));
    if (!save_primitives.empty())
      paco::io::saveVertexGroups(save_primitives + "/" + file.stem().string() + ".bvg",
                                 paco::io::toVertexGroups(primitives));
    std::printf("| %s | %zu", file.stem().string().c_str(), primitives.size());
    for (std::size_t c = 0; c < 2; ++c) {
      const Outcome o = runOnce(primitives, mesh, volume, mfcad_configs[c]);
      if (o.chamfer >= 0) chamfers[c].push_back(o.chamfer);
      times[c].push_back(o.seconds);
      cpu_times[c].push_back(o.cpu_seconds);
      closed[c] += o.ok && o.closed;
      under_goal[c] += o.ok && o.cpu_seconds < goals[c];
      good_volume[c] += o.ok && o.volume_error < 0.01;
      std::printf(" | %.3f / %.3f | %s | %s | %s", o.seconds, o.cpu_seconds, o.ok ? (o.closed ? "yes" : "no") : o.status.c_str(),
                  o.ok ? (std::to_string(std::round(1000 * o.volume_error) / 10).substr(0, 5) + " %").c_str() : "-",
                  formatChamfer(o.chamfer).c_str());
    }
    std::printf(" |\n");
    std::fflush(stdout);
  }
  std::printf("\n| backend | parts | CPU median (s) | CPU 95th pct (s) | CPU max (s) | wall median (s) | wall max (s) | closed | CPU under goal | volume within 1 %% | CD median | CD max |\n");
  std::printf("|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|\n");
  for (std::size_t c = 0; c < 2; ++c)
    std::printf("| %s | %zu | %.3f | %.3f | %.3f | %.3f | %.3f | %zu/%zu | %zu/%zu (< %.0f s) | %zu/%zu | %.2f | %.2f |\n",
                mfcad_configs[c].label.c_str(), runs, percentile(cpu_times[c], 0.5), percentile(cpu_times[c], 0.95),
                percentile(cpu_times[c], 1.0), percentile(times[c], 0.5), percentile(times[c], 1.0), closed[c], runs,
                under_goal[c], runs, goals[c], good_volume[c], runs, percentile(chamfers[c], 0.5),
                percentile(chamfers[c], 1.0));
  return 0;
}
