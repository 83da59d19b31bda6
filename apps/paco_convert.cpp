// paco_convert: converts a point cloud or a polygon mesh from one file format to another, and
// optionally moves it to the origin at unit bounding-box diagonal (printing how to undo that).
//   paco_convert scan.pcd scan.ply --normalize
//   paco_convert part.stl part.obj
#include "app_support.h"

#include <paco/common/error.h>
#include <paco/common/normalization.h>
#include <paco/io/cloud_io.h>
#include <paco/io/mesh_io.h>

#include <boost/program_options.hpp>

#include <cstdio>
#include <iostream>
#include <string>

namespace po = boost::program_options;

namespace {

const char kTool[] = "paco_convert";

struct Options {
  std::string input, output;
  bool normalize = false;
  bool drop_non_finite = false;
  std::string pcd_encoding = "binary";
  bool ascii = false;
};

void printHelp(const po::options_description& visible) {
  std::cout << "Usage: " << kTool << " INPUT OUTPUT [options]\n\n"
            << "Converts a point cloud (.pcd .ply .xyz .npy .vg .bvg, the same for output) or a mesh\n"
            << "(.obj .off .ply .stl -> .obj .off .ply .stl); the formats follow the extensions. A .ply\n"
            << "input with faces is a mesh, without faces a cloud.\n\n"
            << visible << std::endl;
}

bool isMeshOnly(const std::string& ext) { return ext == ".obj" || ext == ".off" || ext == ".stl"; }
bool isCloudOnly(const std::string& ext) {
  return ext == ".pcd" || ext == ".xyz" || ext == ".npy" || ext == ".vg" || ext == ".bvg";
}

void printNormalization(const paco::Normalization& norm) {
  std::printf("normalised: centre %.17g %.17g %.17g, scale %.17g\n", norm.center.x(), norm.center.y(),
              norm.center.z(), norm.scale);
  std::printf("  (undo with x = x' / scale + centre)\n");
}

int convertMesh(const Options& o, paco::app::StageTimer& timer) {
  timer.start("load");
  paco::SurfaceMesh mesh = paco::io::loadMesh(o.input);
  timer.stop();
  std::printf("read '%s': %zu vertices, %zu faces\n", o.input.c_str(), mesh.vertices.size(), mesh.faces.size());
  if (o.normalize) {
    timer.start("normalise");
    const auto norm = paco::Normalization::fromBoundingBox(mesh.vertices);
    norm.apply(mesh);
    timer.stop();
    printNormalization(norm);
  }
  timer.start("save");
  paco::app::PendingOutput output(o.output);
  paco::io::saveMesh(output.writePath(), mesh);
  output.commit();
  timer.stop();
  std::printf("wrote '%s': %zu vertices, %zu faces\n", o.output.c_str(), mesh.vertices.size(), mesh.faces.size());
  return 0;
}

int convertCloud(const Options& o, paco::app::StageTimer& timer) {
  paco::io::CloudReadOptions read;
  if (o.drop_non_finite) read.non_finite = paco::io::NonFinitePolicy::Drop;
  paco::io::CloudWriteOptions write;
  if (o.pcd_encoding == "ascii") write.pcd_encoding = paco::io::PcdEncoding::Ascii;
  else if (o.pcd_encoding == "binary") write.pcd_encoding = paco::io::PcdEncoding::Binary;
  else if (o.pcd_encoding == "binary_compressed") write.pcd_encoding = paco::io::PcdEncoding::BinaryCompressed;
  else throw paco::app::UsageError("--pcd-encoding must be ascii, binary or binary_compressed");
  write.ascii_ply = o.ascii;
  // --ascii is the PLY writer's; a PCD's encoding has its own option.
  if (o.ascii && paco::io::extensionOf(o.output) != ".ply")
    throw paco::app::UsageError("--ascii writes an ascii PLY cloud; for '" + o.output +
                                "' drop it" + (paco::io::extensionOf(o.output) == ".pcd" ? " and give --pcd-encoding ascii" : ""));

  timer.start("load");
  paco::io::LabelledCloud cloud = paco::io::loadCloud(o.input, read);
  timer.stop();
  std::printf("read '%s': %zu points%s%s\n", o.input.c_str(), cloud.points.size(),
              cloud.has_normals ? ", with normals" : "", cloud.hasLabels() ? ", with labels" : "");
  if (o.normalize) {
    timer.start("normalise");
    auto norm = paco::Normalization::fromBoundingBox(cloud.points);
    norm.apply(cloud.points);
    // The points were relative to the coordinate offset: the centre to print is the file's.
    norm.center += cloud.coordinate_offset;
    cloud.coordinate_offset.setZero();
    timer.stop();
    printNormalization(norm);
  }
  timer.start("save");
  paco::app::warnIfPcdRoundsFarCoordinates(o.output, cloud.coordinate_offset);
  paco::app::PendingOutput output(o.output);
  paco::io::saveCloud(output.writePath(), cloud, write);
  output.commit();
  timer.stop();
  std::printf("wrote '%s': %zu points\n", o.output.c_str(), cloud.points.size());
  return 0;
}

int run(int argc, char** argv) {
  Options o;
  po::options_description visible("Options");
  visible.add_options()
      ("help,h", "print this help")
      ("normalize", po::bool_switch(&o.normalize), "move to the origin at unit bounding-box diagonal and print the transform")
      ("drop-non-finite", po::bool_switch(&o.drop_non_finite), "drop points with NaN/Inf coordinates (default: fail)")
      ("pcd-encoding", po::value(&o.pcd_encoding)->default_value(o.pcd_encoding), "ascii, binary or binary_compressed")
      ("ascii", po::bool_switch(&o.ascii), "write an ascii PLY cloud instead of a binary one");
  po::options_description all;
  all.add(visible).add_options()("input", po::value(&o.input))("output", po::value(&o.output));
  po::positional_options_description positional;
  positional.add("input", 1).add("output", 1);
  const po::variables_map vm = paco::app::parseCommandLine(argc, argv, all, positional);
  if (vm.count("help")) {
    printHelp(visible);
    return 0;
  }
  if (o.input.empty() || o.output.empty()) throw paco::app::UsageError("expected INPUT and OUTPUT files");
  // The extensions the cloud writer (.pcd .ply .xyz .npy .vg .bvg) and the mesh writer (.obj .off .ply .stl) know.
  paco::app::checkOutputPath(o.output, "OUTPUT", {".pcd", ".ply", ".xyz", ".npy", ".vg", ".bvg", ".obj", ".off", ".stl"});
  paco::app::checkOutputsAreNotInputs({{"INPUT", o.input}}, {{"OUTPUT", o.output}});

  const std::string in_ext = paco::io::extensionOf(o.input), out_ext = paco::io::extensionOf(o.output);
  bool mesh = isMeshOnly(in_ext) || isMeshOnly(out_ext);
  if (!mesh && in_ext == ".ply" && out_ext == ".ply") {
    try {
      mesh = !paco::io::loadMesh(o.input, /*allow_no_faces=*/true).faces.empty();
    } catch (const paco::IoError&) {
      mesh = false;  // the cloud reader reports the problem (or drops NaN points on request)
    }
  }
  if (mesh && (isCloudOnly(in_ext) || isCloudOnly(out_ext)))
    throw paco::app::UsageError("cannot convert between a mesh and a point cloud ('" + in_ext + "' -> '" + out_ext + "')");

  paco::app::StageTimer timer;
  const int rc = mesh ? convertMesh(o, timer) : convertCloud(o, timer);
  timer.print();
  return rc;
}

}  // namespace

int main(int argc, char** argv) {
  return paco::app::runTool(kTool, [&] { return run(argc, argv); });
}
