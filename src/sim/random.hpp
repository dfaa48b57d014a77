#pragma once
// A small, portable random source for the simulator (identical streams on every platform: the
// standard distributions are implementation-defined, so they are not used).
#include <cmath>
#include <cstdint>
#include <random>

namespace slam_mms::sim {

/// SplitMix64 hash: derives independent stream seeds from (seed, stream id).
inline uint64_t MixSeed(uint64_t seed, uint64_t stream) {
  uint64_t z = seed + 0x9E3779B97F4A7C15ULL * (stream + 1);
  z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ULL;
  z = (z ^ (z >> 27)) * 0x94D049BB133111EBULL;
  return z ^ (z >> 31);
}

class Rng {
 public:
  explicit Rng(uint64_t seed) : engine_(seed) {}
  /// Uniform in [0, 1).
  double Uniform() { return static_cast<double>(engine_() >> 11) * (1.0 / 9007199254740992.0); }
  double Uniform(double a, double b) { return a + (b - a) * Uniform(); }
  bool Bernoulli(double p) { return Uniform() < p; }
  /// Standard normal (Box-Muller, both values used).
  double Normal() {
    if (has_spare_) {
      has_spare_ = false;
      return spare_;
    }
    double u1 = Uniform();
    while (u1 <= 1e-300) u1 = Uniform();
    const double u2 = Uniform();
    const double r = std::sqrt(-2.0 * std::log(u1));
    spare_ = r * std::sin(2.0 * M_PI * u2);
    has_spare_ = true;
    return r * std::cos(2.0 * M_PI * u2);
  }
  double Normal(double sigma) { return sigma * Normal(); }
  /// Integer in [a, b].
  int UniformInt(int a, int b) {
    const int k = static_cast<int>(std::floor(Uniform() * (b - a + 1)));
    return a + (k > b - a ? b - a : k);
  }

 private:
  std::mt19937_64 engine_;
  bool has_spare_ = false;
  double spare_ = 0.0;
};

}  // namespace slam_mms::sim
