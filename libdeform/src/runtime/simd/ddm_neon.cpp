// The Direct Delta Mush kernel built for aarch64 Advanced SIMD with its fused multiply-adds (lanes.hpp's mul_add).
// Built only for aarch64, where every CPU runs it; Isa::neon selects it (direct_delta_mush.cpp).
#define DEFORM_DDM_ENTRY direct_delta_mush_neon
#define DEFORM_DDM_REDUCED_ENTRY direct_delta_mush_reduced_neon
#include "ddm_kernel.inl"
