// The lattice kernel built for the compiler's baseline target (SSE2 on x86-64, NEON on ARM64) without fused
// multiply-adds (lanes.hpp), for every CPU: the copy Isa::portable runs (lattice_evaluate.cpp chooses).
#define DEFORM_LANES_UNFUSED 1
#define DEFORM_KERNEL_ENTRY evaluate_lattice_portable
#include "lattice_kernel.inl"
