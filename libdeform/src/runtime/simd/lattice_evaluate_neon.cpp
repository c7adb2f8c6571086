// The lattice kernel built for aarch64 Advanced SIMD with its fused multiply-adds (lanes.hpp's mul_add), 16 lanes as
// four q registers. Built only for aarch64, where every CPU runs it; Isa::neon selects it (lattice_evaluate.cpp).
#define DEFORM_KERNEL_ENTRY evaluate_lattice_neon
#include "lattice_kernel.inl"
