#include "app_support.h"

#include <paco/common/error.h>

#include <cstdio>
#include <filesystem>
#include <iostream>
#include <stdexcept>

namespace paco::app {

int runTool(const std::string& tool_name, const std::function<int()>& body) {
  try {
    return body();
  } catch (const UsageError& e) {
    std::cerr << tool_name << ": " << e.what() << "\nTry '" << tool_name << " --help'." << std::endl;
    return 2;
  } catch (const paco::Error& e) {
    std::cerr << tool_name << ": error: " << e.what() << std::endl;
    return 1;
  } catch (const std::exception& e) {
    std::cerr << tool_name << ": error: " << e.what() << std::endl;
    return 1;
  }
}

boost::program_options::variables_map parseCommandLine(
    int argc, char** argv, const boost::program_options::options_description& options,
    const boost::program_options::positional_options_description& positional) {
  namespace po = boost::program_options;
  po::variables_map vm;
  try {
    po::store(po::command_line_parser(argc, argv).options(options).positional(positional).run(), vm);
    po::notify(vm);
  } catch (const po::error& e) {
    throw UsageError(e.what());
  }
  return vm;
}

namespace {
std::string temporaryName(const std::string& final_path) {
  const std::filesystem::path p(final_path);
  // "mesh.obj" -> "mesh.partial.obj": the extension stays last so writers still pick the format.
  return (p.parent_path() / (p.stem().string() + ".partial" + p.extension().string())).string();
}
}  // namespace

PendingOutput::PendingOutput(std::string final_path)
    : final_path_(std::move(final_path)), temp_path_(temporaryName(final_path_)) {}

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
  stages_.emplace_back(current_, std::chrono::duration<double>(std::chrono::steady_clock::now() - started_).count());
  current_.clear();
}

double StageTimer::seconds(const std::string& stage) const {
  double total = 0;
  for (const auto& [name, s] : stages_)
    if (name == stage) total += s;
  return total;
}

void StageTimer::print() const {
  double total = 0;
  std::printf("timing:\n");
  for (const auto& [name, s] : stages_) {
    std::printf("  %-14s %8.3f s\n", name.c_str(), s);
    total += s;
  }
  std::printf("  %-14s %8.3f s\n", "total", total);
}

}  // namespace paco::app
