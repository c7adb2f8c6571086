// The lattice kernel built for AVX-512 (this file alone is compiled with -mavx512f; see CMakeLists.txt). Only called
// when isa_available(Isa::avx512) (lattice_evaluate.cpp).
#define DEFORM_KERNEL_ENTRY evaluate_lattice_avx512
#include "lattice_kernel.inl"
