// The project's random generator: a seeded 64-bit Mersenne twister with its own
// uniform and Gaussian draws, so that a seed gives the same numbers with any standard
// library (std::normal_distribution's algorithm is implementation-defined).
#pragma once

#include <cmath>
#include <cstdint>
#include <random>

#include "core/math_constants.h"

namespace twinsim {

class Rng {
 public:
  explicit Rng(std::uint64_t seed = 1) : engine_(seed) {}

  // Uniform in [0, 1), 53 random bits.
  double Uniform() { return static_cast<double>(engine_() >> 11) * 0x1.0p-53; }
  double Uniform(double lo, double hi) { return lo + (hi - lo) * Uniform(); }
  // Integer uniform in [0, n).
  std::uint64_t Index(std::uint64_t n) { return static_cast<std::uint64_t>(Uniform() * static_cast<double>(n)); }

  // Standard normal by Box-Muller; the second value is kept for the next call.
  double Gaussian() {
    if (has_spare_) {
      has_spare_ = false;
      return spare_;
    }
    double u1 = Uniform();
    while (u1 <= 0) u1 = Uniform();
    const double u2 = Uniform();
    const double r = std::sqrt(-2.0 * std::log(u1));
    spare_ = r * std::sin(2 * kPi * u2);
    has_spare_ = true;
    return r * std::cos(2 * kPi * u2);
  }
  double Gaussian(double sigma) { return sigma * Gaussian(); }

  // A new generator whose stream is derived from this one's seed and `stream`,
  // for independent, reproducible sub-streams (one per robot, per worker).
  static Rng Derived(std::uint64_t seed, std::uint64_t stream) {
    std::seed_seq seq{static_cast<std::uint32_t>(seed), static_cast<std::uint32_t>(seed >> 32),
                      static_cast<std::uint32_t>(stream), static_cast<std::uint32_t>(stream >> 32)};
    Rng r;
    r.engine_.seed(seq);
    return r;
  }

 private:
  std::mt19937_64 engine_;
  double spare_ = 0;
  bool has_spare_ = false;
};

}  // namespace twinsim
