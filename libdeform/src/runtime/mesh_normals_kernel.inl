// The vertex-normal block kernel, included once per instruction set (mesh_normals_portable.cpp, _avx2.cpp and
// _avx512.cpp, each compiled with its own flags). Everything here has internal linkage but the one entry point the
// includer names with DEFORM_NORMALS_ENTRY, so the copies never meet at link time.
//
// A block of 16 triangles at a time, structure of arrays: standard C++ loops over the 16 lanes around scalar code,
// which the compiler vectorises (one zmm register per lane vector under AVX-512, two ymm under AVX2, four xmm for the
// portable copy on x86-64, NEON on ARM). Per block: gather the corners, cross product, corner angles; then each
// corner's weighted normal is added to its point's sum (one 16-byte add per corner under AVX-512). Last, 16 points at
// a time, the sums are normalised.
#include <algorithm>
#include <cmath>
#include <numbers>
#if defined(__AVX512F__)
#include <immintrin.h>
#endif

#include "lanes.hpp"
#include "mesh_normals_kernel.hpp"

namespace {

constexpr int lanes = int(deform::detail::triangles_per_block);

// glm's dot and cross with the products fused (mul_add), as the copies compiled for FMA hardware can.
inline float dot(const glm::vec3& a, const glm::vec3& b) { return mul_add(a.x, b.x, mul_add(a.y, b.y, a.z * b.z)); }
inline glm::vec3 cross(const glm::vec3& a, const glm::vec3& b) {
  return {mul_add(a.y, b.z, -(a.z * b.y)), mul_add(a.z, b.x, -(a.x * b.z)), mul_add(a.x, b.y, -(a.y * b.x))};
}

#if defined(__AVX512F__)
// Transposes 16 lanes of (x, y, z) into 16 quads (x, y, z, 0), lane j's at quads[4 j .. 4 j + 3].
inline void store_quads(const float* vx, const float* vy, const float* vz, float* quads) {
  const __m512 zero = _mm512_setzero_ps();
  for (int half = 0; half < 2; ++half) {
    const int o = 8 * half;
    const __m512i interleave = _mm512_setr_epi32(o, 16 + o, o + 1, 17 + o, o + 2, 18 + o, o + 3, 19 + o, o + 4, 20 + o,
                                                 o + 5, 21 + o, o + 6, 22 + o, o + 7, 23 + o);
    const __m512 x = _mm512_loadu_ps(vx), y = _mm512_loadu_ps(vy), z = _mm512_loadu_ps(vz);
    const __m512 xy = _mm512_permutex2var_ps(x, interleave, y);   // x0 y0 x1 y1 ... x7 y7 of this half
    const __m512 z0 = _mm512_permutex2var_ps(z, interleave, zero);  // z0 0 z1 0 ... z7 0
    for (int quarter = 0; quarter < 2; ++quarter) {
      const int q = 8 * quarter;
      const __m512i pairs = _mm512_setr_epi32(q, q + 1, 16 + q, 17 + q, q + 2, q + 3, 18 + q, 19 + q, q + 4, q + 5,
                                              20 + q, 21 + q, q + 6, q + 7, 22 + q, 23 + q);
      _mm512_storeu_ps(quads + 32 * half + 16 * quarter, _mm512_permutex2var_ps(xy, pairs, z0));
    }
  }
}
#endif

}  // namespace

namespace deform::detail {

void DEFORM_NORMALS_ENTRY(const NormalsKernelArgs& args) noexcept {
  for (std::size_t p = 0; p < args.point_count; ++p) args.point_sums[p] = glm::vec4(0.0f);
  const std::size_t blocks = (args.triangle_count + lanes - 1) / lanes;
  for (std::size_t block = 0; block < blocks; ++block) {
    const int count = int(std::min<std::size_t>(lanes, args.triangle_count - block * lanes));
    const std::uint32_t* points = args.block_points + 3 * lanes * block;  // corner k of lane j: points[16 k + j]
    alignas(64) float corner[3][3][lanes];                                 // corner, axis, lane
    for (int k = 0; k < 3; ++k)
      for (int lane = 0; lane < lanes; ++lane) {
        const glm::vec3& position = args.positions[points[k * lanes + lane]];
        corner[k][0][lane] = position.x, corner[k][1][lane] = position.y, corner[k][2][lane] = position.z;
      }
    // contribution[k][axis][lane]: corner k's angle times the unit normal of the lane's triangle. Degenerate lanes
    // (zero or NaN area; padding) contribute exactly nothing, whatever their corners hold.
    alignas(64) float contribution[3][3][lanes];
    for (int lane = 0; lane < lanes; ++lane) {
      const glm::vec3 a(corner[0][0][lane], corner[0][1][lane], corner[0][2][lane]);
      const glm::vec3 b(corner[1][0][lane], corner[1][1][lane], corner[1][2][lane]);
      const glm::vec3 c(corner[2][0][lane], corner[2][1][lane], corner[2][2][lane]);
      const glm::vec3 ab = b - a, ac = c - a, bc = c - b;
      const glm::vec3 area_normal = cross(ab, ac);  // |area_normal| = 2 * area = |e1||e2| sin(corner angle)
      const float twice_area = std::sqrt(dot(area_normal, area_normal));
      const float angle_a = corner_angle(twice_area, dot(ab, ac));
      const float angle_b = corner_angle(twice_area, -dot(ab, bc));
      const float third = std::numbers::pi_v<float> - angle_a - angle_b;
      const float angle_c = third > 0.0f ? third : 0.0f;
      const float inverse_area = 1.0f / twice_area;
      const bool degenerate = !(twice_area > 0.0f);
      const float weight[3] = {angle_a * inverse_area, angle_b * inverse_area, angle_c * inverse_area};
      DEFORM_UNROLL
      for (int k = 0; k < 3; ++k)
        DEFORM_UNROLL
        for (int axis = 0; axis < 3; ++axis)
          contribution[k][axis][lane] = degenerate ? 0.0f : weight[k] * area_normal[axis];
    }
    // Corner by corner across the lanes: neighbouring triangles share points, and adding to the same point twice
    // in a row would make each add wait for the one before.
    for (int k = 0; k < 3; ++k) {
#if defined(__AVX512F__)
      alignas(64) float quads[4 * lanes];
      store_quads(contribution[k][0], contribution[k][1], contribution[k][2], quads);
      for (int lane = 0; lane < count; ++lane) {
        float* sum = &args.point_sums[points[k * lanes + lane]].x;
        _mm_storeu_ps(sum, _mm_add_ps(_mm_loadu_ps(sum), _mm_load_ps(quads + 4 * lane)));
      }
#else
      for (int lane = 0; lane < count; ++lane)
        args.point_sums[points[k * lanes + lane]] +=
            glm::vec4(contribution[k][0][lane], contribution[k][1][lane], contribution[k][2][lane], 0.0f);
#endif
    }
  }
  // 16 points at a time, so that the square roots and divisions are lane vectors. A cancelled or NaN sum gives
  // (0, 0, 0).
  for (std::size_t first = 0; first < args.point_count; first += lanes) {
    const int count = int(std::min<std::size_t>(lanes, args.point_count - first));
    glm::vec4* sums = args.point_sums + first;
    alignas(64) float sum[3][lanes] = {};
    for (int lane = 0; lane < count; ++lane)
      sum[0][lane] = sums[lane].x, sum[1][lane] = sums[lane].y, sum[2][lane] = sums[lane].z;
    alignas(64) float normal[3][lanes];
    for (int lane = 0; lane < lanes; ++lane) {
      const float x = sum[0][lane], y = sum[1][lane], z = sum[2][lane];
      const float length = std::sqrt(mul_add(x, x, mul_add(y, y, z * z)));
      const bool kept = length > cancelled_normal_sum;
      normal[0][lane] = kept ? x / length : 0.0f;
      normal[1][lane] = kept ? y / length : 0.0f;
      normal[2][lane] = kept ? z / length : 0.0f;
    }
    for (int lane = 0; lane < count; ++lane)
      sums[lane] = glm::vec4(normal[0][lane], normal[1][lane], normal[2][lane], 0.0f);
  }
}

}  // namespace deform::detail
