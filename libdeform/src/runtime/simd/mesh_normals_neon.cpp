// The vertex-normal block kernel built for aarch64 Advanced SIMD with its fused multiply-adds (lanes.hpp's mul_add),
// 16 lanes as four q registers. Built only for aarch64, where every CPU runs it; Isa::neon selects it
// (mesh_normals.cpp).
#define DEFORM_NORMALS_ENTRY vertex_normals_neon
#include "mesh_normals_kernel.inl"
