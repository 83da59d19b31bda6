#pragma once
// Internal: a seeded random source whose output is fixed by the C++ standard (mt19937_64 and our
// own conversions), so that datasets are byte-identical across compilers and standard libraries.
#include <paco/common/angles.h>
#include <cmath>
#include <cstdint>
#include <random>

namespace paco::data::detail {

/// SplitMix64 finaliser: mixes a seed with a stream id into an independent seed.
inline std::uint64_t mixSeed(std::uint64_t seed, std::uint64_t stream) {
  std::uint64_t z = seed + 0x9E3779B97F4A7C15ull * (stream + 1);
  z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ull;
  z = (z ^ (z >> 27)) * 0x94D049BB133111EBull;
  return z ^ (z >> 31);
}

class Rng {
 public:
  explicit Rng(std::uint64_t seed) : engine_(seed) {}
  /// Uniform in [0, 1) with 53 random bits.
  double uniform() { return static_cast<double>(engine_() >> 11) * (1.0 / 9007199254740992.0); }
  double uniform(double lo, double hi) { return lo + (hi - lo) * uniform(); }
  /// Standard normal by the Box-Muller transform.
  double normal() {
    if (has_spare_) {
      has_spare_ = false;
      return spare_;
    }
    double u = uniform();
    while (u <= 0.0) u = uniform();
    const double v = uniform();
    const double r = std::sqrt(-2.0 * std::log(u));
    spare_ = r * std::sin(2.0 * kPi * v);
    has_spare_ = true;
    return r * std::cos(2.0 * kPi * v);
  }
  /// Uniform integer in [0, n), n > 0.
  std::uint64_t index(std::uint64_t n) { return static_cast<std::uint64_t>(uniform() * static_cast<double>(n)) % n; }
  /// Uniform integer in [lo, hi].
  int integer(int lo, int hi) { return lo + static_cast<int>(index(static_cast<std::uint64_t>(hi - lo + 1))); }

 private:
  std::mt19937_64 engine_;
  double spare_ = 0.0;
  bool has_spare_ = false;
};

}  // namespace paco::data::detail
