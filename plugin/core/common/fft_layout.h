// Internal to the FFTs (fft.cc, fft_real.cc; the butterflies: fft_kernels.h):
// row strides, the aligned scratch layout and the in-register block
// transposes. Not a public API.
#ifndef MJTOUCH_COMMON_FFT_LAYOUT_H_
#define MJTOUCH_COMMON_FFT_LAYOUT_H_

#include <algorithm>
#include <cstddef>
#include <cstdint>
#include <cstring>
#include <vector>

namespace mjtouch {
namespace fft_detail {

// Row strides an odd multiple of 8 elements: not a power of two (those put
// the radix streams of a stage in the same cache sets), and whole 32-byte
// vectors, so that with SplitScratch's aligned arrays rows start on a vector
// boundary (unaligned rows cross a cache line every other load).
inline int PaddedStride(int n) {
  int r = (n + 7) / 8 * 8;
  if ((r / 8) % 2 == 0) r += 8;
  return r;
}

// dst[c * ds + r] = src[r * ss + c], r < rows, c < cols: 8 x 8 (float) or
// 4 x 4 (double) blocks transposed in registers (GCC vector extensions:
// AVX2 or SSE2 pairs, no intrinsics), the edges one by one. Data movement
// only: the same bits on every path.
typedef float V8f __attribute__((vector_size(32)));
typedef double V4d __attribute__((vector_size(32)));
// Macros, not functions: 32-byte vectors passed by value warn of an ABI
// change (-Wpsabi) in the SSE2 build.
#define MJTOUCH_LOAD(v, p) std::memcpy(&(v), (p), sizeof(v))
#define MJTOUCH_STORE(p, v)                \
  do {                                     \
    const auto tmp_ = (v);                 \
    std::memcpy((p), &tmp_, sizeof(tmp_)); \
  } while (0)

inline
    __attribute__((always_inline)) void Block(const float* src, size_t ss, float* dst, size_t ds) {
  V8f r[8];
  for (int k = 0; k < 8; ++k) MJTOUCH_LOAD(r[k], src + k * ss);
  V8f t[8], u[8];
  for (int k = 0; k < 4; ++k) {
    t[2 * k] = __builtin_shufflevector(r[2 * k], r[2 * k + 1], 0, 8, 1, 9, 4, 12, 5, 13);
    t[2 * k + 1] = __builtin_shufflevector(r[2 * k], r[2 * k + 1], 2, 10, 3, 11, 6, 14, 7, 15);
  }
  for (int k = 0; k < 2; ++k) {
    const V8f a = t[4 * k], b = t[4 * k + 1], c = t[4 * k + 2], d = t[4 * k + 3];
    u[4 * k] = __builtin_shufflevector(a, c, 0, 1, 8, 9, 4, 5, 12, 13);
    u[4 * k + 1] = __builtin_shufflevector(a, c, 2, 3, 10, 11, 6, 7, 14, 15);
    u[4 * k + 2] = __builtin_shufflevector(b, d, 0, 1, 8, 9, 4, 5, 12, 13);
    u[4 * k + 3] = __builtin_shufflevector(b, d, 2, 3, 10, 11, 6, 7, 14, 15);
  }
  for (int k = 0; k < 4; ++k) {
    MJTOUCH_STORE(dst + k * ds, __builtin_shufflevector(u[k], u[k + 4], 0, 1, 2, 3, 8, 9, 10, 11));
    MJTOUCH_STORE(dst + (k + 4) * ds,
                  __builtin_shufflevector(u[k], u[k + 4], 4, 5, 6, 7, 12, 13, 14, 15));
  }
}

inline __attribute__((always_inline)) void Block(const double* src, size_t ss, double* dst,
                                                 size_t ds) {
  V4d r[4];
  for (int k = 0; k < 4; ++k) MJTOUCH_LOAD(r[k], src + k * ss);
  const V4d t0 = __builtin_shufflevector(r[0], r[1], 0, 4, 2, 6);
  const V4d t1 = __builtin_shufflevector(r[0], r[1], 1, 5, 3, 7);
  const V4d t2 = __builtin_shufflevector(r[2], r[3], 0, 4, 2, 6);
  const V4d t3 = __builtin_shufflevector(r[2], r[3], 1, 5, 3, 7);
  MJTOUCH_STORE(dst, __builtin_shufflevector(t0, t2, 0, 1, 4, 5));
  MJTOUCH_STORE(dst + ds, __builtin_shufflevector(t1, t3, 0, 1, 4, 5));
  MJTOUCH_STORE(dst + 2 * ds, __builtin_shufflevector(t0, t2, 2, 3, 6, 7));
  MJTOUCH_STORE(dst + 3 * ds, __builtin_shufflevector(t1, t3, 2, 3, 6, 7));
}
#undef MJTOUCH_LOAD
#undef MJTOUCH_STORE

template <typename T>
struct VecOf;
template <>
struct VecOf<float> {
  typedef V8f type;
};
template <>
struct VecOf<double> {
  typedef V4d type;
};

// Scratch for a 2D transform: the y-pass work arrays (W each) and the
// stages' ping-pong arrays (max(W, spectrum) each), in one buffer.
template <typename T>
inline void SplitScratch(size_t W, size_t spectrum, std::vector<T>* scratch, T** wr, T** wi, T** sr,
                         T** si) {
  // 64-byte aligned arrays (see PaddedStride), each a whole number of lines.
  constexpr size_t kLine = 64 / sizeof(T);
  W = (W + kLine - 1) / kLine * kLine;
  const size_t S = (std::max(W, spectrum) + kLine - 1) / kLine * kLine;
  scratch->resize(2 * W + 2 * S + kLine);
  const size_t misalign = reinterpret_cast<uintptr_t>(scratch->data()) % 64 / sizeof(T);
  *wr = scratch->data() + (misalign ? kLine - misalign : 0);
  *wi = *wr + W;
  *sr = *wi + W;
  *si = *sr + S;
}

}  // namespace fft_detail
}  // namespace mjtouch

#endif  // MJTOUCH_COMMON_FFT_LAYOUT_H_
