// Deterministic stratified sampling of triangles, seeded per element pair so
// that results do not depend on the thread that computes them.
#pragma once

#include "radmesh/geometry.h"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <numbers>

namespace radmesh {

// SplitMix64: small, fast, and good enough for stratification jitter.
class SplitMix {
public:
  explicit SplitMix(uint64_t seed) : s_(seed) {}
  uint64_t next() {
    uint64_t z = (s_ += 0x9E3779B97F4A7C15ULL);
    z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ULL;
    z = (z ^ (z >> 27)) * 0x94D049BB133111EBULL;
    return z ^ (z >> 31);
  }
  double uniform() { return static_cast<double>(next() >> 11) * 0x1.0p-53; }
  // The stream as after n calls of next(), without making their values.
  void skip(uint64_t n) { s_ += n * 0x9E3779B97F4A7C15ULL; }

private:
  uint64_t s_;
};

inline uint64_t pair_seed(uint64_t a, uint64_t b) { return (a * 0x100000001B3ULL) ^ (b + 0x9E3779B97F4A7C15ULL); }

// Cosine-distributed directions about a unit normal: stratum k of a
// side x side grid (two draws of rng).
struct CosineHemisphere {
  Vec3 n, u, v;
  explicit CosineHemisphere(const Vec3& normal) : n(normal) {
    const Vec3 a = std::abs(n.x) < 0.9 ? Vec3(1, 0, 0) : Vec3(0, 1, 0);
    u = glm::normalize(glm::cross(n, a));
    v = glm::cross(n, u);
  }
  Vec3 direction(int k, int side, SplitMix& rng) const {
    const double r1 = ((k / side) + rng.uniform()) / side, r2 = ((k % side) + rng.uniform()) / side;
    const double r = std::sqrt(r1), phi = 2.0 * std::numbers::pi * r2;
    return r * std::cos(phi) * u + r * std::sin(phi) * v + std::sqrt(std::max(0.0, 1.0 - r1)) * n;
  }
};

// Maps the unit square onto triangle (a, b, c), area-uniformly.
inline Vec3 triangle_point(const Vec3& a, const Vec3& b, const Vec3& c, double u, double v) {
  const double s = std::sqrt(u);
  return (1.0 - s) * a + s * (1.0 - v) * b + s * v * c;
}

// The last i in [begin, end) with cum[i] <= target, for a nondecreasing
// cum (prefix sums of areas) with cum[begin] <= target: what
// std::upper_bound over (begin, end) gives, less one. Sampling an area
// fraction u of a long run of triangles, a binary search misses the cache
// at nearly every step: the search starts at
// begin + u (end - begin), where equal areas would put target, and
// gallops from there to a bracket that it then halves.
inline int area_index(const double* cum, int begin, int end, double target, double u) {
  const int n = end - begin;
  const int guess = begin + std::clamp(static_cast<int>(u * n), 0, n - 1);
  int below = guess, above = end;  // cum[below] <= target; the answer is in [below, above)
  if (cum[guess] <= target) {
    for (int step = 1; guess + step < end; step *= 2) {
      if (cum[guess + step] > target) {
        above = guess + step;
        break;
      }
      below = guess + step;
    }
  } else {
    above = guess;
    below = begin;
    for (int step = 1; guess - step > begin; step *= 2) {
      if (cum[guess - step] <= target) {
        below = guess - step;
        break;
      }
      above = guess - step;
    }
  }
  return static_cast<int>(std::upper_bound(cum + below + 1, cum + above, target) - cum - 1);
}

// Side of the stratification grid for at least `rays` samples.
inline int strata_side(int rays) {
  int k = 1;
  while (k * k < rays) ++k;
  return k;
}

}  // namespace radmesh
