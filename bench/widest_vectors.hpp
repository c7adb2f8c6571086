#pragma once
// DEFORM_WIDEST_VECTORS: a plain loop compiled for the widest vector unit the CPU has (GCC and Clang function
// clones, picked at load time), as the skinning kernels are. The memory bounds (memory/*, skin/same_bytes) use it:
// built for the baseline alone, memory/add was bound by its own instructions on an AVX-512 machine and reported less
// than the skinning kernel itself streams.
#if defined(__x86_64__) && (defined(__GNUC__) || defined(__clang__))
#define DEFORM_WIDEST_VECTORS __attribute__((target_clones("avx512f", "avx2", "default")))
#else
#define DEFORM_WIDEST_VECTORS
#endif
