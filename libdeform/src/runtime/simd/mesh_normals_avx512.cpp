// The vertex-normal block kernel built for AVX-512 (this file alone is compiled with -mavx512f; see CMakeLists.txt).
// Only called when isa_available(Isa::avx512) (mesh_normals.cpp).
#define DEFORM_NORMALS_ENTRY vertex_normals_avx512
#include "mesh_normals_kernel.inl"
