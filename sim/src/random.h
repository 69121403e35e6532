#pragma once
// Portable random numbers for the simulator. std::mt19937_64 is fully specified by the standard;
// std::normal_distribution and std::uniform_real_distribution are not, so we map the raw 64-bit
// output to doubles and normals ourselves.

#include <Eigen/Core>
#include <cmath>
#include <cstdint>
#include <random>

namespace skerry::sim {

/// SplitMix64 finaliser (Steele, Lea, Flood 2014): decorrelates seeds of neighbouring streams.
inline std::uint64_t SplitMix64(std::uint64_t x) {
  x += 0x9E3779B97F4A7C15ULL;
  x = (x ^ (x >> 30)) * 0xBF58476D1CE4E5B9ULL;
  x = (x ^ (x >> 27)) * 0x94D049BB133111EBULL;
  return x ^ (x >> 31);
}

/// Independent named streams so that e.g. adding a GNSS outage never changes the IMU noise.
enum class RngStream : std::uint64_t {
  kWavePhases = 1,
  kImuBiasInitial = 2,
  kImuNoise = 3,
  kGnssNoise = 4,
  kGnssDrift = 5,
  kGnssHeading = 6,
  kImuScaleMisalignment = 7,
  kGnssSlowDrift = 8,
  kGnssMultipath = 9,
  kGnssTiming = 10,
  kPoseFix = 11,
  kCameraNoise = 12,
  kHarbourBoats = 13,
  kLidarNoise = 14,
  kAerialImage = 15,
  kTwinGnssOutliers = 16,
  kTwinGnssSolve = 17,
  kDemError = 18,
};

class Rng {
 public:
  Rng(std::uint64_t seed, RngStream stream)
      : engine_(SplitMix64(seed ^ SplitMix64(static_cast<std::uint64_t>(stream)))) {}

  /// Uniform in [0, 1) from the top 53 bits.
  double Uniform() { return static_cast<double>(engine_() >> 11) * 0x1.0p-53; }

  /// Standard normal by the Box-Muller transform (both values used).
  double Normal() {
    if (has_spare_) {
      has_spare_ = false;
      return spare_;
    }
    const double u1 = 1.0 - Uniform();  // (0, 1]: log is finite
    const double u2 = Uniform();
    const double radius = std::sqrt(-2.0 * std::log(u1));
    const double angle = 2.0 * 3.14159265358979323846 * u2;
    spare_ = radius * std::sin(angle);
    has_spare_ = true;
    return radius * std::cos(angle);
  }

  Eigen::Vector3d Normal3() {
    const double x = Normal();
    const double y = Normal();
    const double z = Normal();
    return Eigen::Vector3d(x, y, z);
  }

 private:
  std::mt19937_64 engine_;
  bool has_spare_ = false;
  double spare_ = 0.0;
};

}  // namespace skerry::sim
