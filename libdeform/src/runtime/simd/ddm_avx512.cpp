// The Direct Delta Mush kernel built for AVX-512 (16 lanes, one zmm register each; see CMakeLists.txt). Only called
// when isa_available(Isa::avx512) (direct_delta_mush.cpp).
#define DEFORM_DDM_ENTRY direct_delta_mush_avx512
#define DEFORM_DDM_REDUCED_ENTRY direct_delta_mush_reduced_avx512
#include "ddm_kernel.inl"
