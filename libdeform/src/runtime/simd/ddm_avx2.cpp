// The Direct Delta Mush kernel built for AVX2 + FMA (this file alone is compiled with -mavx2 -mfma; see
// CMakeLists.txt). Only called when isa_available(Isa::avx2) (direct_delta_mush.cpp).
#define DEFORM_DDM_ENTRY direct_delta_mush_avx2
#define DEFORM_DDM_REDUCED_ENTRY direct_delta_mush_reduced_avx2
#include "ddm_kernel.inl"
