// The Direct Delta Mush kernel built for WebAssembly SIMD128 (-msimd128). Built only into a WebAssembly build with
// DEFORM_WASM_SIMD128; Isa::simd128 selects it (direct_delta_mush.cpp). No fused multiply-add: rounds as portable.
#define DEFORM_DDM_ENTRY direct_delta_mush_simd128
#define DEFORM_DDM_REDUCED_ENTRY direct_delta_mush_reduced_simd128
#include "ddm_kernel.inl"
