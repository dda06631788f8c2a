// Function multi-versioning for the vectorized numerical kernels.
//
// DRIFTLAB_SIMD_CLONES before a function definition compiles it twice on x86-64 with GCC: an AVX2
// clone, picked once at load time on CPUs that have AVX2, and a baseline x86-64 clone. Only AVX2
// is enabled, not FMA, so no multiply-add is contracted and both clones give the same bits.
// Elsewhere the macro is empty and the function is compiled for the build's target.
#pragma once

#if defined(__x86_64__) && defined(__GNUC__) && !defined(__clang__)
#define DRIFTLAB_SIMD_CLONES __attribute__((target_clones("avx2", "default")))
#else
#define DRIFTLAB_SIMD_CLONES
#endif
