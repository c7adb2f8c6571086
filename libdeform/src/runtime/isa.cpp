// The one CPU-feature query of the runtime kernels (isa.hpp).
#include "deform/runtime/isa.hpp"

#include "deform/runtime/portable.hpp"

namespace deform {
namespace {

struct CpuFeatures {
  bool avx2 = false;
  bool avx512 = false;
  bool neon = false;
  bool simd128 = false;
};

CpuFeatures read_cpu_features() noexcept {
  CpuFeatures features;
#if defined(DEFORM_X86_KERNELS)
  // libgcc fills the table __builtin_cpu_supports reads from a constructor of its own; initialising it here makes the
  // answer right even when the first query comes from another static initialiser.
  DEFORM_X86_CPU_INIT();
  features.avx2 = DEFORM_X86_CPU_SUPPORTS("avx2") && DEFORM_X86_CPU_SUPPORTS("fma");
  features.avx512 = features.avx2 && DEFORM_X86_CPU_SUPPORTS("avx512f") && DEFORM_X86_CPU_SUPPORTS("avx512dq") &&
                    DEFORM_X86_CPU_SUPPORTS("avx512vl") && DEFORM_X86_CPU_SUPPORTS("avx512bw");
#endif
#if defined(DEFORM_NEON_KERNELS)
  features.neon = true;  // Advanced SIMD and FMA are part of the aarch64 base architecture: nothing to ask the CPU
#endif
#if defined(DEFORM_SIMD128_KERNELS)
  // WebAssembly cannot ask: an engine without SIMD128 refuses the whole module, so the build decides.
  features.simd128 = true;
#endif
  return features;
}

const CpuFeatures& cpu_features() noexcept {
  static const CpuFeatures features = read_cpu_features();
  return features;
}

}  // namespace

bool isa_available(Isa isa) noexcept {
  switch (isa) {
    case Isa::automatic:
    case Isa::portable: return true;
    case Isa::avx2: return cpu_features().avx2;
    case Isa::avx512: return cpu_features().avx512;
    case Isa::neon: return cpu_features().neon;
    case Isa::simd128: return cpu_features().simd128;
  }
  return false;
}

Isa isa_best() noexcept {
  if (cpu_features().neon) return Isa::neon;
  if (cpu_features().simd128) return Isa::simd128;
  if (cpu_features().avx512) return Isa::avx512;
  if (cpu_features().avx2) return Isa::avx2;
  return Isa::portable;
}

const char* isa_name(Isa isa) noexcept {
  switch (isa) {
    case Isa::automatic: return "automatic";
    case Isa::portable: return "portable";
    case Isa::avx2: return "avx2";
    case Isa::avx512: return "avx512";
    case Isa::neon: return "neon";
    case Isa::simd128: return "simd128";
  }
  return "unknown";
}

}  // namespace deform
