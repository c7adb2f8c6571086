// The vertex-normal block kernel built for AVX-512 (this file alone is compiled with -mavx512f; see
// libdeform/CMakeLists.txt). Only called after a runtime check of the CPU (mesh_normals.cpp).
#define DEFORM_NORMALS_ENTRY vertex_normals_avx512
#include "mesh_normals_kernel.inl"
