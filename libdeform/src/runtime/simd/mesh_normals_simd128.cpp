// The vertex-normal block kernel built for WebAssembly SIMD128 (-msimd128), 16 lanes as four v128 values. Built only
// into a WebAssembly build with DEFORM_WASM_SIMD128; Isa::simd128 selects it (mesh_normals.cpp). SIMD128 has no
// fused multiply-add, so it rounds as the portable copy does.
#define DEFORM_NORMALS_ENTRY vertex_normals_simd128
#include "mesh_normals_kernel.inl"
