// Portable guards for the hand-vectorised code (x86-64, aarch64, macOS).
#pragma once

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

// MJTOUCH_TARGET_CLONES_AVX512: also an AVX-512 copy, for loops written in
// 16-float GCC vectors (one 512-bit register per vector; two AVX2 ones, four
// SSE2 / NEON ones elsewhere: the same elementwise operations, so the same
// bits on every ISA). Where there are no clones: the one baseline copy. Only
// for straight-line vector code: a 16-float vector kept across a loop on a
// narrower ISA is lowered through the stack (stress_fold.cc's sums, 3.7x
// slower on AVX2, hold native-width vectors in a copy per width instead).
#if MJTOUCH_X86_SIMD && defined(__ELF__) && defined(__GNUC__) && !defined(__clang__)
#define MJTOUCH_TARGET_CLONES_AVX512 \
  __attribute__((target_clones("avx512f", "avx2", "default")))
#endif
#ifndef MJTOUCH_TARGET_CLONES_AVX512
#define MJTOUCH_TARGET_CLONES_AVX512
#endif
