// The vertex-normal block kernel built for AVX2 + FMA (this file alone is compiled with -mavx2 -mfma; see
// CMakeLists.txt). Only called when isa_available(Isa::avx2) (mesh_normals.cpp).
#define DEFORM_NORMALS_ENTRY vertex_normals_avx2
#include "mesh_normals_kernel.inl"
