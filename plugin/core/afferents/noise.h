// Internal to afferents/: the receptors' noise and variant draws, pure
// functions of (seed, stream, count) so that runs are reproducible and
// independent of thread order.
#ifndef MJTOUCH_AFFERENTS_NOISE_H_
#define MJTOUCH_AFFERENTS_NOISE_H_

#include <cmath>
#include <cstdint>

namespace mjtouch {
namespace afferent_noise {

constexpr double kTwoPi = 6.283185307179586;

inline uint64_t SplitMix64(uint64_t x) {
  x += 0x9e3779b97f4a7c15ULL;
  x = (x ^ (x >> 30)) * 0xbf58476d1ce4e5b9ULL;
  x = (x ^ (x >> 27)) * 0x94d049bb133111ebULL;
  return x ^ (x >> 31);
}

// Standard normal deviate, a pure function of (seed, stream, count);
// NormalHashed takes SplitMix64(seed) (ReceptorStepper: hashed once).
// ReceptorStepper::NoiseRun evaluates the same expressions for several
// receptors at once: change both together.
inline double NormalHashed(uint64_t seed_hash, uint64_t stream, uint64_t count) {
  const uint64_t h1 = SplitMix64(SplitMix64(seed_hash ^ stream) ^ count);
  const uint64_t h2 = SplitMix64(h1);
  const double u1 = (static_cast<double>(h1 >> 11) + 0.5) * 0x1p-53;  // (0, 1)
  const double u2 = static_cast<double>(h2 >> 11) * 0x1p-53;
  return std::sqrt(-2.0 * std::log(u1)) * std::cos(kTwoPi * u2);
}
inline double Normal(uint64_t seed, uint64_t stream, uint64_t count) {
  return NormalHashed(SplitMix64(seed), stream, count);
}

}  // namespace afferent_noise
}  // namespace mjtouch

#endif  // MJTOUCH_AFFERENTS_NOISE_H_
