// Portable guards for the hand-vectorised code (x86-64, aarch64, macOS).
#pragma once

#include <cstdlib>
#include <cstring>

// MJTOUCH_X86_SIMD: 1 where the x86 intrinsics (<emmintrin.h>) may be used.
// MJTOUCH_NO_X86_INTRINSICS (CMake -DMJTOUCH_PORTABLE_SIMD=ON) builds the
// portable paths on x86 too, so that they are tested on the CI machine.
#if (defined(__x86_64__) || defined(__i386__)) && !defined(MJTOUCH_NO_X86_INTRINSICS)
#define MJTOUCH_X86_SIMD 1
#else
#define MJTOUCH_X86_SIMD 0
#endif

// MJTOUCH_TARGET_CLONES: an AVX2 copy of the function next to the baseline
// one, picked at load time through an ifunc. Only x86 has the "avx2" target
// and only ELF has ifuncs (not Mach-O, not PE); Clang (14-18) rejects it on
// templates and on member functions. Elsewhere it is empty: the one baseline
// copy, which rounds like the AVX2 one (no FMA contraction).
#if MJTOUCH_X86_SIMD && defined(__ELF__) && defined(__GNUC__) && !defined(__clang__)
#define MJTOUCH_TARGET_CLONES __attribute__((target_clones("avx2", "default")))
#endif
#ifndef MJTOUCH_TARGET_CLONES
#define MJTOUCH_TARGET_CLONES
#endif

// MJTOUCH_ISA_COPIES(name, params, args): for loops that keep vectors
// across iterations or need FMA, where target_clones will not do (it cannot
// give each copy its own vector width or contraction; GCC's "avx2" has no
// FMA; a 16-float vector kept across a loop on a narrower ISA is lowered
// through the stack). Compiles
// name##Body<W, kFma> args once per ISA (W: floats per native vector) and
// defines `void name params`, which calls the copy picked once at run time:
// AVX-512 (16), AVX2 + FMA (8), else the baseline (4: SSE2; NEON on aarch64,
// whose FMA is always there). In the FMA copies GCC contracts a * b + c
// (MJTOUCH_CONTRACT), so bodies whose arithmetic is IEEE fma give the same
// bits in every copy. MJTOUCH_SUM_LANES=8 or 4 in the environment picks a
// narrower copy (tests: every copy on one CPU).
#if defined(__GNUC__) && !defined(__clang__)
#define MJTOUCH_CONTRACT __attribute__((optimize("fp-contract=fast")))
#else
#define MJTOUCH_CONTRACT
#endif
#if defined(__aarch64__)
#define MJTOUCH_BASELINE_FMA true
#define MJTOUCH_BASELINE_CONTRACT MJTOUCH_CONTRACT
#else
#define MJTOUCH_BASELINE_FMA false
#define MJTOUCH_BASELINE_CONTRACT
#endif

namespace mjtouch {

enum class Isa { kBaseline, kAvx2Fma, kAvx512 };

inline Isa PickIsa() {
#if MJTOUCH_X86_SIMD && defined(__GNUC__)
  __builtin_cpu_init();
  const bool avx512 = __builtin_cpu_supports("avx512f");
  const bool avx2_fma = __builtin_cpu_supports("avx2") && __builtin_cpu_supports("fma");
#else
  const bool avx512 = false, avx2_fma = false;
#endif
  const char* lanes = std::getenv("MJTOUCH_SUM_LANES");
  if (lanes && std::strcmp(lanes, "4") == 0) return Isa::kBaseline;
  if (lanes && std::strcmp(lanes, "8") == 0) return avx2_fma ? Isa::kAvx2Fma : Isa::kBaseline;
  return avx512 ? Isa::kAvx512 : avx2_fma ? Isa::kAvx2Fma : Isa::kBaseline;
}

inline Isa ChosenIsa() {
  static const Isa isa = PickIsa();
  return isa;
}

}  // namespace mjtouch

#if MJTOUCH_X86_SIMD && defined(__GNUC__)
#define MJTOUCH_X86_ISA_COPIES(name, params, args)                                 \
  __attribute__((target("avx2,fma"))) MJTOUCH_CONTRACT void name##Avx2Fma params { \
    name##Body<8, true> args;                                                      \
  }                                                                                \
  __attribute__((target("avx512f"))) MJTOUCH_CONTRACT void name##Avx512 params {   \
    name##Body<16, true> args;                                                     \
  }
#define MJTOUCH_X86_ISA_SWITCH(name, args)                    \
  switch (::mjtouch::ChosenIsa()) {                           \
    case ::mjtouch::Isa::kAvx512: return name##Avx512 args;   \
    case ::mjtouch::Isa::kAvx2Fma: return name##Avx2Fma args; \
    case ::mjtouch::Isa::kBaseline: break;                    \
  }
#else
#define MJTOUCH_X86_ISA_COPIES(name, params, args)
#define MJTOUCH_X86_ISA_SWITCH(name, args)
#endif
#define MJTOUCH_ISA_COPIES(name, params, args)           \
  MJTOUCH_BASELINE_CONTRACT void name##Baseline params { \
    name##Body<4, MJTOUCH_BASELINE_FMA> args;            \
  }                                                      \
  MJTOUCH_X86_ISA_COPIES(name, params, args)             \
  void name params {                                     \
    MJTOUCH_X86_ISA_SWITCH(name, args)                   \
    name##Baseline args;                                 \
  }
