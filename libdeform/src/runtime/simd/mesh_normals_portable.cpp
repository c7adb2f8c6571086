// The vertex-normal kernel built for the compiler's baseline target (SSE2 on x86-64, NEON on ARM64) without fused
// multiply-adds (lanes.hpp), for every CPU: the copy Isa::portable runs (mesh_normals.cpp chooses).
#define DEFORM_LANES_UNFUSED 1
#define DEFORM_NORMALS_ENTRY vertex_normals_portable
#include "mesh_normals_kernel.inl"
