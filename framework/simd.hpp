// Function multi-versioning for the vectorized numerical kernels.
//
// DRIFTLAB_SIMD_CLONES before a function definition compiles it twice on x86-64 with GCC: an AVX2
// clone, picked once at load time on CPUs that have AVX2, and a baseline x86-64 clone. Only AVX2
// is enabled, not FMA, so no multiply-add is contracted and both clones give the same bits.
// Elsewhere the macro is empty and the function is compiled for the build's target.
//
// For the few kernels that need AVX2 intrinsics (<immintrin.h>), DRIFTLAB_AVX2_INTRINSICS is
// defined on x86-64 GCC and Clang: a function marked DRIFTLAB_AVX2_TARGET may use them and must only
// be called when cpu_has_avx2() is true; the caller keeps a portable path for the other case.
#pragma once

#if defined(__x86_64__) && defined(__GNUC__) && !defined(__clang__)
#define DRIFTLAB_SIMD_CLONES __attribute__((target_clones("avx2", "default")))
#else
#define DRIFTLAB_SIMD_CLONES
#endif

#if defined(__x86_64__) && defined(__GNUC__)
#define DRIFTLAB_AVX2_INTRINSICS 1
#define DRIFTLAB_AVX2_TARGET __attribute__((target("avx2,popcnt")))

namespace driftlab {

// True on CPUs with AVX2 and POPCNT (checked once).
inline bool cpu_has_avx2() {
  static const bool has = __builtin_cpu_supports("avx2") && __builtin_cpu_supports("popcnt");
  return has;
}

}  // namespace driftlab
#endif
