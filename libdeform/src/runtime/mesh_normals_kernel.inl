// The vertex-normal block kernel, included once per instruction set (mesh_normals.cpp: the portable copy;
// mesh_normals_avx2.cpp, mesh_normals_avx512.cpp: compiled with their own flags). Everything here has internal linkage
// but the one entry point the includer names with DEFORM_NORMALS_ENTRY, so the copies never meet at link time.
//
// A block of 16 triangles as lane vectors of GCC's vector extensions, structure of arrays: one zmm register of 16
// lanes under AVX-512, two passes of 8 under AVX2, else four passes of one 4-lane register (SSE2; NEON elsewhere). Per block: gather the corners,
// cross product, corner angles; then each corner's weighted normal is added to its point's sum (one 16-byte add per
// corner under AVX-512). Last, a register's worth of points at a time, the sums are normalised.
#include <algorithm>
#include <cmath>
#include <cstring>
#if defined(__AVX512F__)
#include <immintrin.h>
#endif

#include "mesh_normals_kernel.hpp"

namespace {

#if defined(__AVX512F__)
constexpr int width = 16;
#elif defined(__AVX2__)
constexpr int width = 8;
#else
constexpr int width = 4;
#endif
typedef float Lanes __attribute__((vector_size(4 * width)));
constexpr int block_size = int(deform::detail::triangles_per_block);
static_assert(block_size % width == 0);

struct LaneVec3 {
  Lanes x, y, z;
};

inline Lanes load(const float* p) {
  Lanes r;
  std::memcpy(&r, p, sizeof r);
  return r;
}

inline LaneVec3 operator-(const LaneVec3& a, const LaneVec3& b) { return {a.x - b.x, a.y - b.y, a.z - b.z}; }
inline Lanes dot(const LaneVec3& a, const LaneVec3& b) { return a.x * b.x + a.y * b.y + a.z * b.z; }
inline LaneVec3 cross(const LaneVec3& a, const LaneVec3& b) {
  return {a.y * b.z - a.z * b.y, a.z * b.x - a.x * b.z, a.x * b.y - a.y * b.x};
}

#if defined(__AVX512F__)
// Transposes 16 lanes of (x, y, z) into 16 quads (x, y, z, 0), lane j's at quads[4 j .. 4 j + 3].
inline void store_quads(const LaneVec3& v, float* quads) {
  const __m512 zero = _mm512_setzero_ps();
  for (int half = 0; half < 2; ++half) {
    const int o = 8 * half;
    const __m512i interleave = _mm512_setr_epi32(o, 16 + o, o + 1, 17 + o, o + 2, 18 + o, o + 3, 19 + o, o + 4, 20 + o,
                                                 o + 5, 21 + o, o + 6, 22 + o, o + 7, 23 + o);
    const __m512 xy = _mm512_permutex2var_ps(v.x, interleave, v.y);   // x0 y0 x1 y1 ... x7 y7 of this half
    const __m512 z0 = _mm512_permutex2var_ps(v.z, interleave, zero);  // z0 0 z1 0 ... z7 0
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
  const std::size_t blocks = (args.triangle_count + block_size - 1) / block_size;
  for (std::size_t block = 0; block < blocks; ++block) {
    const int count = int(std::min<std::size_t>(block_size, args.triangle_count - block * block_size));
    for (int first = 0; first < count; first += width) {
      const std::uint32_t* points = args.block_points + 3 * block_size * block + first;  // corner k: points[16 k + j]
      float gathered[3][3][width];  // corner, axis, lane
      for (int k = 0; k < 3; ++k)
        for (int lane = 0; lane < width; ++lane) {
          const glm::vec3 position = args.positions[points[k * block_size + lane]];
          for (int axis = 0; axis < 3; ++axis) gathered[k][axis][lane] = position[axis];
        }
      LaneVec3 corner[3];
      for (int k = 0; k < 3; ++k) corner[k] = {load(gathered[k][0]), load(gathered[k][1]), load(gathered[k][2])};
      const LaneVec3 ab = corner[1] - corner[0], ac = corner[2] - corner[0], bc = corner[2] - corner[1];
      const LaneVec3 area_normal = cross(ab, ac);  // |area_normal| = 2 * area = |e1||e2| sin(corner angle)
      Lanes twice_area = dot(area_normal, area_normal);
      for (int lane = 0; lane < width; ++lane) twice_area[lane] = std::sqrt(twice_area[lane]);
      const Lanes angle_a = corner_angle(twice_area, dot(ab, ac));
      const Lanes angle_b = corner_angle(twice_area, -dot(ab, bc));
      Lanes angle_c = std::numbers::pi_v<float> - angle_a - angle_b;
      angle_c = angle_c > 0.0f ? angle_c : 0.0f;
      // Degenerate lanes (zero or NaN area; padding) contribute exactly nothing, whatever their corners hold.
      const auto nondegenerate = twice_area > 0.0f;
      const Lanes zero = {};
      const Lanes inverse_area = 1.0f / twice_area;
      const Lanes weight[3] = {angle_a * inverse_area, angle_b * inverse_area, angle_c * inverse_area};
      // Corner by corner across the lanes: neighbouring triangles share points, and adding to the same point twice
      // in a row would make each add wait for the one before.
      const int used = std::min(width, count - first);
      for (int k = 0; k < 3; ++k) {
        const LaneVec3 contribution = {nondegenerate ? weight[k] * area_normal.x : zero,
                                       nondegenerate ? weight[k] * area_normal.y : zero,
                                       nondegenerate ? weight[k] * area_normal.z : zero};
#if defined(__AVX512F__)
        alignas(64) float quads[4 * width];
        store_quads(contribution, quads);
        for (int lane = 0; lane < used; ++lane) {
          float* sum = &args.point_sums[points[k * block_size + lane]].x;
          _mm_storeu_ps(sum, _mm_add_ps(_mm_loadu_ps(sum), _mm_load_ps(quads + 4 * lane)));
        }
#else
        for (int lane = 0; lane < used; ++lane)
          args.point_sums[points[k * block_size + lane]] +=
              glm::vec4(contribution.x[lane], contribution.y[lane], contribution.z[lane], 0.0f);
#endif
      }
    }
  }
  // A register's worth of points at a time, so that the square roots and divisions are lane vectors. A cancelled or
  // NaN sum gives (0, 0, 0).
  for (std::size_t first = 0; first < args.point_count; first += width) {
    const int count = int(std::min<std::size_t>(width, args.point_count - first));
    glm::vec4* sums = args.point_sums + first;
    LaneVec3 sum = {};
    for (int lane = 0; lane < count; ++lane) {
      sum.x[lane] = sums[lane].x;
      sum.y[lane] = sums[lane].y;
      sum.z[lane] = sums[lane].z;
    }
    Lanes length = dot(sum, sum);
    for (int lane = 0; lane < width; ++lane) length[lane] = std::sqrt(length[lane]);
    const auto kept = length > cancelled_normal_sum;
    const Lanes zero = {};
    const LaneVec3 normal = {kept ? sum.x / length : zero, kept ? sum.y / length : zero, kept ? sum.z / length : zero};
    for (int lane = 0; lane < count; ++lane)
      sums[lane] = glm::vec4(normal.x[lane], normal.y[lane], normal.z[lane], 0.0f);
  }
}

}  // namespace deform::detail
