// The lattice kernel built for AVX2 + FMA (this file alone is compiled with -mavx2 -mfma; see CMakeLists.txt). Only
// called when isa_available(Isa::avx2) (lattice_evaluate.cpp).
#define DEFORM_KERNEL_ENTRY evaluate_lattice_avx2
#include "lattice_kernel.inl"
