// SpringCrowdJob's lane kernel built for AVX2 (this file alone is compiled with -mavx2, without FMA; see
// CMakeLists.txt). Only called when isa_available(Isa::avx2) (spring_chains.cpp).
#define DEFORM_SPRING_ENTRY spring_lanes_avx2
#include "spring_lanes_kernel.inl"
