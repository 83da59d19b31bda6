// Network benchmark (not a test): parameter count, training-step throughput and batch-1
// inference latency of the PaCo network for each preset, on synthetic segmented clouds.
//   bench_network --preset cpu --threads 2            # one preset
//   bench_network --threads 2                         # both presets, Markdown table
//   bench_network --preset cpu --set width=256 --set decoder_depth=6   # explore a variant
#include <paco/common/allocator.h>
#include <paco/common/blas.h>
#include <paco/completion/network.h>
#include <paco/encoding/model_config.h>

#include <boost/program_options.hpp>

#include <algorithm>
#include <chrono>
#include <ctime>
#include <cstdio>
#include <iostream>
#include <string>
#include <vector>

namespace {

using Clock = std::chrono::steady_clock;

// A batch of clouds of `n` points on the 6 faces of random boxes, labelled by face.
paco::NetworkInput syntheticBatch(int64_t batch, int64_t n, uint64_t seed) {
  torch::manual_seed(seed);
  auto face = torch::randint(0, 6, {batch, n}, torch::kLong);
  auto uv = torch::rand({batch, n, 3}) - 0.5;
  auto axis = face.remainder(3);
  auto side = torch::where(face >= 3, torch::full({batch, n}, 0.5), torch::full({batch, n}, -0.5));
  auto points = uv.clone();
  auto normals = torch::zeros({batch, n, 3});
  for (int a = 0; a < 3; ++a) {
    auto on = axis.eq(a);
    points.select(2, a).masked_scatter_(on, side.masked_select(on));
    normals.select(2, a).masked_scatter_(on, torch::sign(side).masked_select(on));
  }
  return {points * 0.57, normals, face};
}

double seconds(Clock::time_point start) {
  return std::chrono::duration<double>(Clock::now() - start).count();
}

double cpuSeconds() { return double(std::clock()) / CLOCKS_PER_SEC; }

// Wall times on a shared machine depend on its load; process CPU time does not (much), so both
// are reported: on an idle machine with T threads, wall ~ CPU / T at best.
struct Result {
  std::string name;
  int64_t parameters = 0;
  double train_samples_per_second = 0, train_step_seconds = 0, train_step_cpu_seconds = 0;
  double inference_ms = 0, inference_cpu_ms = 0;
};

Result run(const paco::ModelConfig& config, int batch, int train_steps, int inference_runs,
           int points) {
  Result result;
  result.name = config.name;
  torch::manual_seed(0);
  paco::PacoNetwork net(config);
  result.parameters = paco::parameterCount(*net);

  // Training step: forward + backward of a simple loss over every output + an Adam step.
  if (train_steps > 0) {
    net->train();
    torch::optim::AdamW optimizer(net->parameters(), torch::optim::AdamWOptions(1e-4));
    auto input = syntheticBatch(batch, points, 1);
    auto step = [&] {
      optimizer.zero_grad();
      auto out = net->forward(input);
      auto loss = out.points.pow(2).mean() + out.offsets.pow(2).mean() +
                  out.logits.pow(2).mean() + out.candidate_scores.pow(2).mean() +
                  (1 - out.normals.select(2, 2).abs()).mean();
      loss.backward();
      optimizer.step();
    };
    step();  // warm-up
    const auto start = Clock::now();
    const double cpu_start = cpuSeconds();
    for (int i = 0; i < train_steps; ++i) step();
    result.train_step_seconds = seconds(start) / train_steps;
    result.train_step_cpu_seconds = (cpuSeconds() - cpu_start) / train_steps;
    result.train_samples_per_second = batch / result.train_step_seconds;
  }

  net->eval();
  torch::NoGradGuard no_grad;
  auto input = syntheticBatch(1, points, 2);
  net->forward(input);  // warm-up
  std::vector<double> times;
  const double cpu_start = cpuSeconds();
  for (int i = 0; i < inference_runs; ++i) {
    const auto start = Clock::now();
    net->forward(input);
    times.push_back(seconds(start) * 1e3);
  }
  result.inference_cpu_ms = (cpuSeconds() - cpu_start) * 1e3 / inference_runs;
  std::sort(times.begin(), times.end());
  result.inference_ms = times[times.size() / 2];  // median
  return result;
}

}  // namespace

int main(int argc, char** argv) {
  std::setvbuf(stdout, nullptr, _IOLBF, 0);  // rows appear as they are measured
  namespace po = boost::program_options;
  po::options_description options("bench_network options");
  std::vector<std::string> presets, overrides;
  int threads = 2, batch = 16, train_steps = 5, inference_runs = 20, points = 2048;
  options.add_options()("help,h", "show this help")(
      "preset", po::value(&presets)->multitoken(), "presets to run (default: cpu paper)")(
      "set", po::value(&overrides), "override a config field, e.g. --set width=256 (repeatable)")(
      "threads", po::value(&threads)->default_value(2), "LibTorch threads")(
      "batch", po::value(&batch)->default_value(16), "training batch size")(
      "train-steps", po::value(&train_steps)->default_value(5), "timed training steps (0: skip)")(
      "inference-runs", po::value(&inference_runs)->default_value(20), "timed batch-1 forwards")(
      "points", po::value(&points)->default_value(2048), "points per input cloud")(
      "default-malloc", "leave the C library's allocator as it is (the tools keep freed memory for reuse)");
  po::variables_map vm;
  try {
    po::store(po::parse_command_line(argc, argv, options), vm);
    po::notify(vm);
  } catch (const std::exception& e) {
    std::cerr << "bench_network: " << e.what() << "\n" << options;
    return 2;
  }
  if (vm.count("help")) {
    std::cout << options;
    return 0;
  }
  if (presets.empty()) presets = {"cpu", "paper"};
  const bool kept = !vm.count("default-malloc") && paco::keepFreedMemoryForReuse();
  paco::warnIfSlowBlas();
  at::set_num_threads(threads);
  std::printf("threads %d, batch %d, %d points per cloud, %s\n\n", threads, batch, points,
              kept ? "freed memory kept for reuse" : "the C library's default allocator");
  std::printf("| preset | parameters | train step wall s (batch %d) | train samples/s | train step CPU s "
              "| batch-1 inference wall ms (median) | batch-1 inference CPU ms |\n",
              batch);
  std::printf("|---|---|---|---|---|---|---|\n");
  for (const auto& name : presets) {
    paco::ModelConfig config = paco::ModelConfig::preset(name);
    for (const auto& o : overrides) {
      const auto eq = o.find('=');
      if (eq == std::string::npos) {
        std::cerr << "bench_network: --set needs field=value\n";
        return 2;
      }
      std::string json = config.toJson();
      const std::string key = "\"" + o.substr(0, eq) + "\": ";
      const auto at = json.find(key);
      if (at == std::string::npos) {
        std::cerr << "bench_network: unknown field " << o.substr(0, eq) << "\n";
        return 2;
      }
      const auto value_start = at + key.size();
      auto value_end = json.find(",\n", value_start);
      if (value_end == std::string::npos) value_end = json.find("\n", value_start);
      json.replace(value_start, value_end - value_start, o.substr(eq + 1));
      config = paco::ModelConfig::fromJson(json);
      config.name = name + "*";
    }
    config.validate();
    const Result r = run(config, batch, train_steps, inference_runs, points);
    std::printf("| %s | %.2f M | %.3f | %.1f | %.3f | %.1f | %.1f |\n", r.name.c_str(),
                r.parameters / 1e6, r.train_step_seconds, r.train_samples_per_second,
                r.train_step_cpu_seconds, r.inference_ms, r.inference_cpu_ms);
    std::fflush(stdout);
  }
  return 0;
}
