// The Direct Delta Mush kernel built for the compiler's baseline target (SSE2 on x86-64) without fused multiply-adds
// (lanes.hpp), for every CPU: what Isa::portable runs (direct_delta_mush.cpp chooses).
#define DEFORM_LANES_UNFUSED 1
#define DEFORM_DDM_ENTRY direct_delta_mush_portable
#define DEFORM_DDM_REDUCED_ENTRY direct_delta_mush_reduced_portable
#include "ddm_kernel.inl"
