// SpringCrowdJob's lane kernel, included once per instruction set (spring_lanes_portable.cpp, _avx2.cpp, each
// compiled with its own flags). Everything here has internal linkage but the one entry point the includer names with
// DEFORM_SPRING_ENTRY, so the copies never meet at link time.
//
// One chain of up to 8 members (one a lane) through all of a step's whole sub-steps: the animated points sampled on
// their cubic, the chain's colliders placed, then its links (substep()'s arithmetic per lane, in its order, its
// branches as selects). The chain's kept state stays in the lanes from the first sub-step to the last; the caller puts
// it there and takes it back once a step.
#include <cmath>
#include <cstdint>
#include <cstring>

#include "spring_lanes_kernel.hpp"

namespace {

constexpr int lane_count = deform::detail::spring_lanes;
using Lane = float[lane_count];
constexpr int collider_rows = deform::detail::spring_collider_rows;
constexpr int state_rows = deform::detail::spring_state_rows;
constexpr int end_rows = deform::detail::spring_end_rows;
constexpr std::size_t max_lane_links = deform::detail::spring_max_links;
constexpr std::size_t max_lane_colliders = deform::detail::spring_max_colliders;

// A chain's sub-step constants in lanes: the first head and its velocity, gravity, radius, 1/h and the maps.
struct ChainLanes {
  std::size_t links = 0;
  Lane hx, hy, hz, hvx, hvy, hvz, gx, gy, gz, radius, inverse_h, py, pv, vy, vv, pg, vg;
};

// c ? a : b by bits. A lane loop that writes `x[k] = c ? a : x[k]` is a conditional store to GCC, which it does not
// vectorise ("control flow in loop"); the bit select is a plain store, and exact (it picks a or b, NaNs included).
// Through memcpy rather than std::bit_cast, which emscripten 3.1.6's libc++ lacks; compilers make it a plain move.
inline float pick(bool c, float a, float b) noexcept {
  const std::uint32_t mask = 0u - std::uint32_t(c);
  std::uint32_t ua, ub;
  std::memcpy(&ua, &a, 4);
  std::memcpy(&ub, &b, 4);
  const std::uint32_t picked = (ua & mask) | (ub & ~mask);
  float out;
  std::memcpy(&out, &picked, 4);
  return out;
}

void links_lanes(const ChainLanes& in, const float* sampled, float* state, const float* colliders,
                 std::size_t collider_count) noexcept {
  // substep()'s links for lane_count members in structure-of-arrays lanes: each line of substep (and of glm's products
  // it calls) written per lane with its operations in the same order, and its branches as selects, so that each lane
  // rounds exactly as the member alone and the loops over the lanes become vector code. The chain's sampled points
  // (`sampled`, 3 rows a point) and kept state (`state`, 9 rows a joint: position, velocity, rest) are already in lanes
  // and the state stays there between sub-steps (SpringChains::advance_together). What a link hands the next (bend,
  // head, its velocity) stays in the lanes along the chain.
  Lane qw, qx, qy, qz, hx, hy, hz, hvx, hvy, hvz;
  const float* gx = in.gx;
  const float* gy = in.gy;
  const float* gz = in.gz;
  const float* radius = in.radius;
  const float* inverse_h = in.inverse_h;
  const float* py = in.py;
  const float* pv = in.pv;
  const float* vy = in.vy;
  const float* vv = in.vv;
  const float* pg = in.pg;
  const float* vg = in.vg;
  for (int k = 0; k < lane_count; ++k) {
    qw[k] = 1.0f, qx[k] = 0.0f, qy[k] = 0.0f, qz[k] = 0.0f;
    hx[k] = in.hx[k], hy[k] = in.hy[k], hz[k] = in.hz[k];
    hvx[k] = in.hvx[k], hvy[k] = in.hvy[k], hvz[k] = in.hvz[k];
  }
  for (std::size_t i = 0; i < in.links; ++i) {
    const float* from = sampled + i * 3 * lane_count;
    const float* to = from + 3 * lane_count;
    float* joint = state + i * state_rows * lane_count;
    Lane ax, ay, az, rx0, ry0, rz0, px0, py0, pz0, vx0, vy0, vz0;
    for (int k = 0; k < lane_count; ++k) {
      ax[k] = to[k] - from[k], ay[k] = to[lane_count + k] - from[lane_count + k];
      az[k] = to[2 * lane_count + k] - from[2 * lane_count + k];
      px0[k] = joint[k], py0[k] = joint[lane_count + k], pz0[k] = joint[2 * lane_count + k];
      vx0[k] = joint[3 * lane_count + k], vy0[k] = joint[4 * lane_count + k], vz0[k] = joint[5 * lane_count + k];
      rx0[k] = joint[6 * lane_count + k], ry0[k] = joint[7 * lane_count + k], rz0[k] = joint[8 * lane_count + k];
    }
    Lane length, bx, by, bz, rx, ry, rz, px, pyy, pz, vx, vyy, vz;
    // keep_length on lane k: back to the bone's length from the head, the velocity along it made the head's.
    const auto keep_length = [&](int k, float& ox, float& oy, float& oz, float& wx, float& wy, float& wz) {
      const float fx = ox - hx[k], fy = oy - hy[k], fz = oz - hz[k];
      const float distance = std::sqrt(fx * fx + fy * fy + fz * fz);
      const float inverse_distance = 1.0f / distance, inverse_length = 1.0f / length[k];
      const bool far = distance > 1e-12f * length[k], long_bone = length[k] > 0.0f;
      const float lx = far ? fx * inverse_distance : long_bone ? bx[k] * inverse_length : bx[k];
      const float ly = far ? fy * inverse_distance : long_bone ? by[k] * inverse_length : by[k];
      const float lz = far ? fz * inverse_distance : long_bone ? bz[k] * inverse_length : bz[k];
      ox = hx[k] + lx * length[k], oy = hy[k] + ly * length[k], oz = hz[k] + lz * length[k];
      const float d = (wx - hvx[k]) * lx + (wy - hvy[k]) * ly + (wz - hvz[k]) * lz;
      wx = wx - d * lx, wy = wy - d * ly, wz = wz - d * lz;
    };
    for (int k = 0; k < lane_count; ++k) {
      length[k] = std::sqrt(ax[k] * ax[k] + ay[k] * ay[k] + az[k] * az[k]);
      // bend * animated (glm): v + ((uv * w) + uuv) * 2, uv = q.xyz × v, uuv = q.xyz × uv.
      const float ux = qy[k] * az[k] - ay[k] * qz[k], uy = qz[k] * ax[k] - az[k] * qx[k],
                  uz = qx[k] * ay[k] - ax[k] * qy[k];
      const float uux = qy[k] * uz - uy * qz[k], uuy = qz[k] * ux - uz * qx[k], uuz = qx[k] * uy - ux * qy[k];
      bx[k] = ax[k] + (ux * qw[k] + uux) * 2.0f, by[k] = ay[k] + (uy * qw[k] + uuy) * 2.0f,
      bz[k] = az[k] + (uz * qw[k] + uuz) * 2.0f;
      rx[k] = hx[k] + bx[k], ry[k] = hy[k] + by[k], rz[k] = hz[k] + bz[k];
      const float rvx = (rx[k] - rx0[k]) * inverse_h[k], rvy = (ry[k] - ry0[k]) * inverse_h[k],
                  rvz = (rz[k] - rz0[k]) * inverse_h[k];
      const float yx = px0[k] - rx0[k], yy = py0[k] - ry0[k], yz = pz0[k] - rz0[k];
      const float wx = vx0[k] - rvx, wy = vy0[k] - rvy, wz = vz0[k] - rvz;
      px[k] = rx[k] + py[k] * yx + pv[k] * wx + pg[k] * gx[k];
      pyy[k] = ry[k] + py[k] * yy + pv[k] * wy + pg[k] * gy[k];
      pz[k] = rz[k] + py[k] * yz + pv[k] * wz + pg[k] * gz[k];
      vx[k] = rvx + vy[k] * yx + vv[k] * wx + vg[k] * gx[k];
      vyy[k] = rvy + vy[k] * yy + vv[k] * wy + vg[k] * gy[k];
      vz[k] = rvz + vy[k] * yz + vv[k] * wz + vg[k] * gz[k];
      keep_length(k, px[k], pyy[k], pz[k], vx[k], vyy[k], vz[k]);
    }
    // Flags as int lanes and combined by & and | (no short circuit): branch-free loops the vectoriser takes.
    int active[lane_count];
    for (int k = 0; k < lane_count; ++k) active[k] = 1;
    for (int round = 0; round < 4; ++round) {
      int pushed[lane_count];
      for (int k = 0; k < lane_count; ++k) pushed[k] = 0;
      for (std::size_t n = 0; n < collider_count; ++n) {
        const float* row = colliders + n * collider_rows * lane_count;
        const float* sx = row;
        const float* sy = row + lane_count;
        const float* sz = row + 2 * lane_count;
        const float* cx = row + 3 * lane_count;
        const float* cy = row + 4 * lane_count;
        const float* cz = row + 5 * lane_count;
        const float* inverse_length2 = row + 6 * lane_count;
        const float* collider_radius = row + 7 * lane_count;
        // First which lanes are inside, without a square root (most tails are outside every capsule); the push only
        // when one is.
        Lane nx, ny, nz, ox, oy, oz, reach;
        int hit[lane_count];
        for (int k = 0; k < lane_count; ++k) {
          const float along =
              ((px[k] - sx[k]) * cx[k] + (pyy[k] - sy[k]) * cy[k] + (pz[k] - sz[k]) * cz[k]) * inverse_length2[k];
          const float t = along < 0.0f ? 0.0f : 1.0f < along ? 1.0f : along;  // std::clamp
          nx[k] = sx[k] + cx[k] * t, ny[k] = sy[k] + cy[k] * t, nz[k] = sz[k] + cz[k] * t;
          ox[k] = px[k] - nx[k], oy[k] = pyy[k] - ny[k], oz[k] = pz[k] - nz[k];
          reach[k] = collider_radius[k] + radius[k];
          const float distance2 = ox[k] * ox[k] + oy[k] * oy[k] + oz[k] * oz[k];
          hit[k] = active[k] & int(!(distance2 >= reach[k] * reach[k]));
        }
        int any_hit = 0;
        for (int k = 0; k < lane_count; ++k) any_hit |= hit[k];
        if (any_hit == 0) continue;
        for (int k = 0; k < lane_count; ++k) {
          const float p0x = px[k], p0y = pyy[k], p0z = pz[k], v0x = vx[k], v0y = vyy[k], v0z = vz[k];
          const float distance = std::sqrt(ox[k] * ox[k] + oy[k] * oy[k] + oz[k] * oz[k]);
          // glm::normalize(rest - nearest + 1e-30f): the direction from the nearest point to the rest.
          const float ex = rx[k] - nx[k] + 1e-30f, ey = ry[k] - ny[k] + 1e-30f, ez = rz[k] - nz[k] + 1e-30f;
          const float inverse_e = 1.0f / std::sqrt(ex * ex + ey * ey + ez * ez);
          const float inverse_o = 1.0f / distance;
          const int apart = int(distance > 1e-12f * reach[k]);
          const float mx = apart ? ox[k] * inverse_o : ex * inverse_e, my = apart ? oy[k] * inverse_o : ey * inverse_e,
                      mz = apart ? oz[k] * inverse_o : ez * inverse_e;
          const float inward = v0x * mx + v0y * my + v0z * mz;
          const int into = hit[k] & int(inward < 0.0f);
          const float qx_ = nx[k] + mx * reach[k], qy_ = ny[k] + my * reach[k], qz_ = nz[k] + mz * reach[k];
          const float ux = v0x - inward * mx, uy = v0y - inward * my, uz = v0z - inward * mz;
          px[k] = pick(hit[k] != 0, qx_, p0x);
          pyy[k] = pick(hit[k] != 0, qy_, p0y);
          pz[k] = pick(hit[k] != 0, qz_, p0z);
          vx[k] = pick(into != 0, ux, v0x);
          vyy[k] = pick(into != 0, uy, v0y);
          vz[k] = pick(into != 0, uz, v0z);
          pushed[k] = pushed[k] | hit[k];
        }
      }
      int any = 0;
      for (int k = 0; k < lane_count; ++k) any |= pushed[k];
      if (any == 0) break;
      for (int k = 0; k < lane_count; ++k) {
        const float p0x = px[k], p0y = pyy[k], p0z = pz[k], v0x = vx[k], v0y = vyy[k], v0z = vz[k];
        float ox = p0x, oy = p0y, oz = p0z, wx = v0x, wy = v0y, wz = v0z;
        keep_length(k, ox, oy, oz, wx, wy, wz);
        const int on = pushed[k];
        active[k] = on;
        px[k] = pick(on != 0, ox, p0x);
        pyy[k] = pick(on != 0, oy, p0y);
        pz[k] = pick(on != 0, oz, p0z);
        vx[k] = pick(on != 0, wx, v0x);
        vyy[k] = pick(on != 0, wy, v0y);
        vz[k] = pick(on != 0, wz, v0z);
      }
    }
    for (int k = 0; k < lane_count; ++k) {
      // shortest_arc(bone, p - head, length²) * bend, as the scalar functions compute it.
      const float norms = length[k] * length[k];
      const float ex = px[k] - hx[k], ey = pyy[k] - hy[k], ez = pz[k] - hz[k];
      const float w = norms + (bx[k] * ex + by[k] * ey + bz[k] * ez);
      const bool opposite = w <= 1e-6f * norms;
      const bool x_major = std::abs(bx[k]) > std::abs(bz[k]);
      const float tw = opposite ? 0.0f : w;
      const float tx = opposite ? (x_major ? -by[k] : 0.0f) : by[k] * ez - ey * bz[k];
      const float ty = opposite ? (x_major ? bx[k] : -bz[k]) : bz[k] * ex - ez * bx[k];
      const float tz = opposite ? (x_major ? 0.0f : by[k]) : bx[k] * ey - ex * by[k];
      const float inverse = 1.0f / std::sqrt(tw * tw + tx * tx + ty * ty + tz * tz);
      const bool turn = norms > 0.0f;
      const float rw = turn ? tw * inverse : 1.0f, rxx = turn ? tx * inverse : 0.0f, ryy = turn ? ty * inverse : 0.0f,
                  rzz = turn ? tz * inverse : 0.0f;
      const float nw = rw * qw[k] - rxx * qx[k] - ryy * qy[k] - rzz * qz[k];
      const float nx = rw * qx[k] + rxx * qw[k] + ryy * qz[k] - rzz * qy[k];
      const float ny = rw * qy[k] + ryy * qw[k] + rzz * qx[k] - rxx * qz[k];
      const float nz = rw * qz[k] + rzz * qw[k] + rxx * qy[k] - ryy * qx[k];
      qw[k] = nw, qx[k] = nx, qy[k] = ny, qz[k] = nz;
    }
    for (int k = 0; k < lane_count; ++k) {
      joint[k] = px[k], joint[lane_count + k] = pyy[k], joint[2 * lane_count + k] = pz[k];
      joint[3 * lane_count + k] = vx[k], joint[4 * lane_count + k] = vyy[k], joint[5 * lane_count + k] = vz[k];
      joint[6 * lane_count + k] = rx[k], joint[7 * lane_count + k] = ry[k], joint[8 * lane_count + k] = rz[k];
    }
    for (int k = 0; k < lane_count; ++k) {  // the next link's head is this tail
      hx[k] = px[k], hy[k] = pyy[k], hz[k] = pz[k];
      hvx[k] = vx[k], hvy[k] = vyy[k], hvz[k] = vz[k];
    }
  }
}

// SpringChains::end_run()'s bend after the step, in lanes: per joint the rigid map taking the animated bone (its
// end points, `ends`) onto the simulated one (the kept positions, `state`), as mat4_cast(bend) with the translation
// head - mat3 · animated head; 12 rows a joint (columns 0, 1, 2 and the translation, xyz each). Each line is
// end_run()'s (shortest_arc, glm's quaternion and matrix products) per lane in its order, its branches as selects.
void bend_lanes(std::size_t links, const float* ends, const float* state, float* corrections) noexcept {
  // Inputs copied into local lanes and results stored from them (as links_lanes does): loops over local arrays only,
  // which the vectoriser takes without alias checks.
  Lane qw, qx, qy, qz, hx, hy, hz;
  for (int k = 0; k < lane_count; ++k) {
    qw[k] = 1.0f, qx[k] = 0.0f, qy[k] = 0.0f, qz[k] = 0.0f;
    hx[k] = ends[6 * lane_count + k], hy[k] = ends[7 * lane_count + k], hz[k] = ends[8 * lane_count + k];
  }
  for (std::size_t i = 0; i < links; ++i) {
    const float* from = ends + i * end_rows * lane_count + 6 * lane_count;  // the animated head (end position)
    const float* to = from + end_rows * lane_count;                         // the animated tail
    const float* joint = state + i * state_rows * lane_count;
    float* out = corrections + i * 12 * lane_count;
    Lane fx, fy, fz, tx0, ty0, tz0, px, py, pz, m[12];
    for (int k = 0; k < lane_count; ++k) {
      fx[k] = from[k], fy[k] = from[lane_count + k], fz[k] = from[2 * lane_count + k];
      tx0[k] = to[k], ty0[k] = to[lane_count + k], tz0[k] = to[2 * lane_count + k];
      px[k] = joint[k], py[k] = joint[lane_count + k], pz[k] = joint[2 * lane_count + k];
    }
    for (int k = 0; k < lane_count; ++k) {
      const float ax = tx0[k] - fx[k], ay = ty0[k] - fy[k], az = tz0[k] - fz[k];
      // bend * (tail - head) (glm): v + ((uv * w) + uuv) * 2, uv = q.xyz × v, uuv = q.xyz × uv.
      const float ux = qy[k] * az - ay * qz[k], uy = qz[k] * ax - az * qx[k], uz = qx[k] * ay - ax * qy[k];
      const float uux = qy[k] * uz - uy * qz[k], uuy = qz[k] * ux - uz * qx[k], uuz = qx[k] * uy - ux * qy[k];
      const float bx = ax + (ux * qw[k] + uux) * 2.0f, by = ay + (uy * qw[k] + uuy) * 2.0f,
                  bz = az + (uz * qw[k] + uuz) * 2.0f;
      // shortest_arc(bone, p - head) * bend, norms = sqrt(|bone|² |p - head|²).
      const float ex = px[k] - hx[k], ey = py[k] - hy[k], ez = pz[k] - hz[k];
      const float norms = std::sqrt((bx * bx + by * by + bz * bz) * (ex * ex + ey * ey + ez * ez));
      const float w = norms + (bx * ex + by * ey + bz * ez);
      const bool opposite = w <= 1e-6f * norms;
      const bool x_major = std::abs(bx) > std::abs(bz);
      const float tw = opposite ? 0.0f : w;
      const float tx = opposite ? (x_major ? -by : 0.0f) : by * ez - ey * bz;
      const float ty = opposite ? (x_major ? bx : -bz) : bz * ex - ez * bx;
      const float tz = opposite ? (x_major ? 0.0f : by) : bx * ey - ex * by;
      const float inverse = 1.0f / std::sqrt(tw * tw + tx * tx + ty * ty + tz * tz);
      const bool turn = norms > 0.0f;
      const float rw = turn ? tw * inverse : 1.0f, rxx = turn ? tx * inverse : 0.0f, ryy = turn ? ty * inverse : 0.0f,
                  rzz = turn ? tz * inverse : 0.0f;
      const float nw = rw * qw[k] - rxx * qx[k] - ryy * qy[k] - rzz * qz[k];
      const float nx = rw * qx[k] + rxx * qw[k] + ryy * qz[k] - rzz * qy[k];
      const float ny = rw * qy[k] + ryy * qw[k] + rzz * qx[k] - rxx * qz[k];
      const float nz = rw * qz[k] + rzz * qw[k] + rxx * qy[k] - ryy * qx[k];
      qw[k] = nw, qx[k] = nx, qy[k] = ny, qz[k] = nz;
      // glm::mat3_cast(bend), then head - mat3 · animated head.
      const float qxx = nx * nx, qyy = ny * ny, qzz = nz * nz, qxz = nx * nz, qxy = nx * ny, qyz = ny * nz,
                  qwx = nw * nx, qwy = nw * ny, qwz = nw * nz;
      const float m00 = 1.0f - 2.0f * (qyy + qzz), m01 = 2.0f * (qxy + qwz), m02 = 2.0f * (qxz - qwy);
      const float m10 = 2.0f * (qxy - qwz), m11 = 1.0f - 2.0f * (qxx + qzz), m12 = 2.0f * (qyz + qwx);
      const float m20 = 2.0f * (qxz + qwy), m21 = 2.0f * (qyz - qwx), m22 = 1.0f - 2.0f * (qxx + qyy);
      m[0][k] = m00, m[1][k] = m01, m[2][k] = m02, m[3][k] = m10, m[4][k] = m11, m[5][k] = m12;
      m[6][k] = m20, m[7][k] = m21, m[8][k] = m22;
      m[9][k] = hx[k] - (m00 * fx[k] + m10 * fy[k] + m20 * fz[k]);
      m[10][k] = hy[k] - (m01 * fx[k] + m11 * fy[k] + m21 * fz[k]);
      m[11][k] = hz[k] - (m02 * fx[k] + m12 * fy[k] + m22 * fz[k]);
      hx[k] = px[k], hy[k] = py[k], hz[k] = pz[k];
    }
    for (int row = 0; row < 12; ++row)
      for (int k = 0; k < lane_count; ++k) out[row * lane_count + k] = m[row][k];
  }
}

}  // namespace

namespace deform::detail {

void DEFORM_SPRING_ENTRY(const SpringLanesArgs& a) noexcept {
  const std::size_t chain_points = a.links + 1;
  const std::size_t sample_points = chain_points + 2 * a.colliders;
  ChainLanes in;
  in.links = a.links;
  for (int k = 0; k < lane_count; ++k) {
    in.gx[k] = a.gravity[k], in.gy[k] = a.gravity[lane_count + k], in.gz[k] = a.gravity[2 * lane_count + k];
    in.radius[k] = a.radius[k];
  }
  double kept = -a.owed;  // the kept state's time relative to this step's start
  const auto whole = [&](double length, const float* maps) {
    kept += length;
    float weights[4];  // sample_points()' Hermite weights, the same for every member (one dt, one kept)
    spring_hermite_weights(kept, a.dt, weights);
    alignas(32) float sampled[(max_lane_links + 1 + 2 * max_lane_colliders) * 3 * lane_count];
    for (std::size_t point = 0; point < sample_points; ++point) {
      const float* e = a.ends + point * end_rows * lane_count;
      float* out = sampled + point * 3 * lane_count;
      for (int axis = 0; axis < 3; ++axis)
        for (int k = 0; k < lane_count; ++k) {  // h00 * p0 + (h10 * h) * v0 + h01 * p1 + (h11 * h) * v1, in order
          const int at = axis * lane_count + k;
          out[at] = weights[0] * e[at] + weights[1] * e[3 * lane_count + at] + weights[2] * e[6 * lane_count + at] +
                    weights[3] * e[9 * lane_count + at];
        }
    }
    // sample_colliders(): the chain's colliders in lanes.
    const float blend = a.dt > 0.0 ? float(std::clamp(kept / a.dt, 0.0, 1.0)) : 1.0f;
    alignas(32) float colliders[max_lane_colliders * collider_rows * lane_count];
    for (std::size_t n = 0; n < a.colliders; ++n) {
      const float* from = sampled + (chain_points + 2 * n) * 3 * lane_count;
      const float* to = from + 3 * lane_count;
      float* row = colliders + n * collider_rows * lane_count;
      for (int k = 0; k < lane_count; ++k) {
        const float ax = to[k] - from[k], ay = to[lane_count + k] - from[lane_count + k],
                    az = to[2 * lane_count + k] - from[2 * lane_count + k];
        const float length2 = ax * ax + ay * ay + az * az;
        const float start = a.radii[2 * n * lane_count + k], end = a.radii[(2 * n + 1) * lane_count + k];
        row[k] = from[k], row[lane_count + k] = from[lane_count + k],
        row[2 * lane_count + k] = from[2 * lane_count + k];
        row[3 * lane_count + k] = ax, row[4 * lane_count + k] = ay, row[5 * lane_count + k] = az;
        row[6 * lane_count + k] = length2 > 0.0f ? 1.0f / length2 : 0.0f;
        row[7 * lane_count + k] = start + (end - start) * blend;
      }
    }
    // As substep() begins: the first head and its velocity over the sub-step; the maps.
    const auto step = float(length);
    for (int k = 0; k < lane_count; ++k) {
      in.inverse_h[k] = 1.0f / step;
      in.hx[k] = sampled[k], in.hy[k] = sampled[lane_count + k], in.hz[k] = sampled[2 * lane_count + k];
      in.hvx[k] = (in.hx[k] - a.heads[k]) * (1.0f / step);
      in.hvy[k] = (in.hy[k] - a.heads[lane_count + k]) * (1.0f / step);
      in.hvz[k] = (in.hz[k] - a.heads[2 * lane_count + k]) * (1.0f / step);
      a.heads[k] = in.hx[k], a.heads[lane_count + k] = in.hy[k], a.heads[2 * lane_count + k] = in.hz[k];
      in.py[k] = maps[k], in.pv[k] = maps[lane_count + k], in.vy[k] = maps[2 * lane_count + k];
      in.vv[k] = maps[3 * lane_count + k], in.pg[k] = maps[4 * lane_count + k], in.vg[k] = maps[5 * lane_count + k];
    }
    links_lanes(in, sampled, a.state, colliders, a.colliders);
  };
  if (a.stall > 0.0) whole(a.stall, a.stall_maps);
  for (std::size_t n = 0; n < a.steps; ++n) whole(a.h, a.maps);
  if (a.corrections != nullptr) bend_lanes(a.links, a.ends, a.state, a.corrections);
}

}  // namespace deform::detail
