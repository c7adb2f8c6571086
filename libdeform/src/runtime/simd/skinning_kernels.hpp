#pragma once
// Internal: the skinning kernels behind SkinningJob::run, one set per instruction set. Each deforms vertices
// [begin, end) of a job that passed the O(1) checks; the per-vertex data is trusted (SkinningJob::validate).
#include <cstddef>
#include <cstring>

#include "deform/runtime/skinning.hpp"
namespace deform::detail {

using SkinKernel = void (*)(const SkinningJob& job, std::size_t begin, std::size_t end) noexcept;

// Portable C++ (skinning_portable.cpp): every method, rigid and scaled DQS palettes.
void skin_lbs_portable(const SkinningJob& job, std::size_t begin, std::size_t end) noexcept;
void skin_dqs_portable(const SkinningJob& job, std::size_t begin, std::size_t end) noexcept;

// The general path (skinning_portable.cpp): vertices extra_vertices[j_begin, j_end) with their four slots and their
// extra influences, LBS or DQS (rigid or scaled), several vertices side by side.
void skin_extra_vertices(const SkinningJob& job, std::size_t j_begin, std::size_t j_end) noexcept;

// 8 vertices per step (skinning_avx2.cpp, compiled with -mavx2 -mfma); scaled DQS goes to the portable kernel. A range
// that is not a whole number of blocks ends (and, streaming, may begin) with a partial block run through the same
// block code, so every vertex gets the same bits wherever a range starts.
void skin_lbs_avx2(const SkinningJob& job, std::size_t begin, std::size_t end) noexcept;
void skin_dqs_avx2(const SkinningJob& job, std::size_t begin, std::size_t end) noexcept;

// 16 vertices per step (skinning_avx512.cpp, compiled with -mavx512f -mavx512dq -mavx512vl -mavx512bw).
void skin_lbs_avx512(const SkinningJob& job, std::size_t begin, std::size_t end) noexcept;
void skin_dqs_avx512(const SkinningJob& job, std::size_t begin, std::size_t end) noexcept;

// 4 vertices per step (skinning_neon.cpp, aarch64 builds).
void skin_lbs_neon(const SkinningJob& job, std::size_t begin, std::size_t end) noexcept;
void skin_dqs_neon(const SkinningJob& job, std::size_t begin, std::size_t end) noexcept;

// 4 vertices per step (skinning_simd128.cpp, WebAssembly builds with DEFORM_WASM_SIMD128).
void skin_lbs_simd128(const SkinningJob& job, std::size_t begin, std::size_t end) noexcept;
void skin_dqs_simd128(const SkinningJob& job, std::size_t begin, std::size_t end) noexcept;

// Byte-addressed stream access shared by the kernels.
inline const float* stream_at(std::span<const float> s, std::size_t stride, std::size_t i) noexcept {
  return reinterpret_cast<const float*>(reinterpret_cast<const unsigned char*>(s.data()) + i * stride);
}
inline float* stream_at(std::span<float> s, std::size_t stride, std::size_t i) noexcept {
  return reinterpret_cast<float*>(reinterpret_cast<unsigned char*>(s.data()) + i * stride);
}

}  // namespace deform::detail
