// Seeding and uniform draws shared by every random kernel (std only, header only).
// splitmix64 (Steele, Lea & Flood 2014) turns a user seed, or a (seed, stream) combination, into a
// well-mixed std::mt19937_64 seed, so nearby seeds give unrelated streams and every parallel task
// can own a stream derived from (seed, task index): same seed, same output on any thread count.
#pragma once

#include <cstddef>
#include <cstdint>
#include <limits>
#include <random>

namespace driftlab {

inline std::uint64_t splitmix64(std::uint64_t x) {
  x += 0x9E3779B97F4A7C15ULL;
  x = (x ^ (x >> 30)) * 0xBF58476D1CE4E5B9ULL;
  x = (x ^ (x >> 27)) * 0x94D049BB133111EBULL;
  return x ^ (x >> 31);
}

// Portable uniform draws (identical on every platform for one seed, unlike std distributions).
class SeededRandom {
 public:
  explicit SeededRandom(std::uint64_t seed) : engine_(splitmix64(seed)) {}

  // Uniform in [0, 1) with 53 random bits.
  double uniform() { return static_cast<double>(engine_() >> 11) * 0x1.0p-53; }

  // Uniform integer in [0, n), unbiased (rejection of the incomplete top range).
  std::size_t index(std::size_t n) {
    const std::uint64_t limit =
        std::numeric_limits<std::uint64_t>::max() - std::numeric_limits<std::uint64_t>::max() % n;
    std::uint64_t draw = engine_();
    while (draw >= limit) draw = engine_();
    return static_cast<std::size_t>(draw % n);
  }

 private:
  std::mt19937_64 engine_;
};

}  // namespace driftlab
