// The lattice kernel built for WebAssembly SIMD128 (-msimd128), 16 lanes as four v128 values. Built only into a
// WebAssembly build with DEFORM_WASM_SIMD128, whose every engine runs it; Isa::simd128 selects it
// (lattice_evaluate.cpp). SIMD128 has no fused multiply-add, so it rounds as the portable copy does.
#define DEFORM_KERNEL_ENTRY evaluate_lattice_simd128
#include "lattice_kernel.inl"
