// Direct Delta Mush (bind_direct_delta_mush, DirectDeltaMushJob): against a plain double-precision reference of the
// paper's equations (a dense smoothing matrix, 4×4 moments, an SVD), the rest pose given back on the built-in
// character and on the rigged models of assimp-testmodels, a rigid motion of the whole skeleton, normals, hostile
// input, ranges and threads, no allocation per frame.
#include <doctest/doctest.h>

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <functional>
#include <limits>
#include <random>
#include <string>
#include <vector>

#include "allocation_counter.hpp"  // counts every allocation of this executable
#include "deform/character/character.hpp"
#include "deform/extras/builtin.hpp"
#include "deform/offline/direct_delta_mush.hpp"
#include "deform/runtime/parallel.hpp"
#if defined(DEFORM_HAVE_IMPORT)
#include "deform/import/import.hpp"
#endif

namespace {

using deform::DirectDeltaMushBinding;
using deform::DirectDeltaMushJob;
using deform::DirectDeltaMushSettings;

float diagonal(std::span<const glm::vec3> p) {
  const deform::Bounds bounds = deform::compute_bounds(p);
  return glm::length(bounds.max - bounds.min);
}

double max_distance(std::span<const glm::vec3> a, std::span<const glm::vec3> b) {
  double d = 0.0;
  for (std::size_t i = 0; i < a.size(); ++i) d = std::max(d, glm::length(glm::dvec3(a[i]) - glm::dvec3(b[i])));
  return d;
}

// A closed tube along +y (rings of `around` points, `rings` of them, capped by a point at each end), weighted to
// `bones` bones along its length with overlapping linear ramps: a limb with joints.
struct Tube {
  deform::Mesh mesh;
  deform::SkinWeights weights;
  int bones = 0;
};

Tube make_tube(int rings, int around, int bones) {
  Tube t;
  t.bones = bones;
  const float length = 4.0f;
  std::vector<glm::vec3>& p = t.mesh.positions;
  p.emplace_back(0.0f, -0.1f, 0.0f);
  for (int r = 0; r < rings; ++r)
    for (int a = 0; a < around; ++a) {
      const float angle = 6.2831853f * float(a) / float(around);
      p.emplace_back(0.5f * std::cos(angle), length * float(r) / float(rings - 1), 0.4f * std::sin(angle));
    }
  p.emplace_back(0.0f, length + 0.1f, 0.0f);
  const std::uint32_t top = std::uint32_t(p.size() - 1);
  std::vector<std::uint32_t>& tri = t.mesh.triangles;
  const auto at = [&](int r, int a) { return std::uint32_t(1 + r * around + (a % around)); };
  for (int a = 0; a < around; ++a) tri.insert(tri.end(), {0u, at(0, a + 1), at(0, a)});
  for (int r = 0; r + 1 < rings; ++r)
    for (int a = 0; a < around; ++a)
      tri.insert(tri.end(), {at(r, a), at(r, a + 1), at(r + 1, a), at(r + 1, a), at(r, a + 1), at(r + 1, a + 1)});
  for (int a = 0; a < around; ++a) tri.insert(tri.end(), {top, at(rings - 1, a), at(rings - 1, a + 1)});
  for (std::uint32_t i = 0; i < p.size(); ++i) t.mesh.vertex_point.push_back(i);
  for (const glm::vec3& q : p) {
    // Bone b's joint at y = length · (b + ½) / bones; weights ramp over a joint's neighbourhood.
    std::vector<std::uint16_t> b;
    std::vector<float> w;
    const float s = q.y / length * float(bones) - 0.5f;
    for (int j = 0; j < bones; ++j) {
      const float v = std::max(0.0f, 1.0f - std::abs(s - float(j)));
      if (v > 0.0f || (j == 0 && s < 0.0f) || (j == bones - 1 && s > float(bones - 1)))
        b.push_back(std::uint16_t(j)), w.push_back(std::max(v, 1e-3f));
    }
    deform::append_influences(t.weights, b, w);
  }
  return t;
}

// The chain's palette: bone j turned by rotations[j] about its joint (y = length · j / bones), each about its parent.
std::vector<glm::mat4> chain_palette(const std::vector<glm::dquat>& turns, float length, glm::dvec3 shift) {
  std::vector<glm::mat4> out;
  glm::dmat4 world(1.0);
  for (std::size_t j = 0; j < turns.size(); ++j) {
    const glm::dvec3 joint(0.0, double(length) * double(j) / double(turns.size()), 0.0);
    const glm::dmat4 local =
        glm::translate(glm::dmat4(1.0), joint) * glm::mat4_cast(turns[j]) * glm::translate(glm::dmat4(1.0), -joint);
    world = world * local;
    out.push_back(glm::mat4(glm::translate(glm::dmat4(1.0), shift) * world));
  }
  return out;
}

glm::dquat random_turn(std::mt19937& random, double max_degrees) {
  std::normal_distribution<double> axis(0.0, 1.0);
  std::uniform_real_distribution<double> angle(-max_degrees, max_degrees);
  glm::dvec3 a{axis(random), axis(random), axis(random)};
  return glm::angleAxis(glm::radians(angle(random)), glm::normalize(a));
}

// --- the reference: the paper's equations in double precision, from the mesh and weights alone ---
// B = (I + λ D⁻¹(D − A))⁻ᵖ dense; Ωᵢⱼ = Σₖ Bᵢₖ wₖⱼ p̃ₖ p̃ₖᵀ (4×4, model coordinates), blended with α toward the
// κ-smoothed weights times the smoothed centroid's moments, normalised per point, with the documented spread
// σᵢ² ψᵢⱼ added to the 3×3 block; per frame Q = Σⱼ Mⱼ Ωᵢⱼ / Q₃₃, its cross-covariance Q₃ₓ₃ − q pᵀ, R = U diag(1, 1,
// det UVᵀ) Vᵀ by Eigen's SVD, and the point R uᵢ + q − R p.
struct Reference {
  std::vector<std::vector<Eigen::Matrix4d>> omega;  // [point][bone]
  std::vector<glm::dvec3> rest;

  Reference(const deform::Mesh& mesh, const deform::SkinWeights& weights, int bones, const DirectDeltaMushSettings& s) {
    const int n = int(mesh.point_count());
    std::vector<std::vector<int>> rings(static_cast<std::size_t>(n));
    for (std::size_t t = 0; t < mesh.triangle_count(); ++t)
      for (int c = 0; c < 3; ++c) {
        const int a = int(mesh.vertex_point[mesh.triangles[3 * t + std::size_t(c)]]);
        const int b = int(mesh.vertex_point[mesh.triangles[3 * t + std::size_t(c + 1) % 3]]);
        if (a == b) continue;
        if (std::find(rings[std::size_t(a)].begin(), rings[std::size_t(a)].end(), b) == rings[std::size_t(a)].end())
          rings[std::size_t(a)].push_back(b), rings[std::size_t(b)].push_back(a);
      }
    const auto smoothing = [&](double step) {
      Eigen::MatrixXd m = Eigen::MatrixXd::Identity(n, n);
      for (int i = 0; i < n; ++i) {
        if (rings[std::size_t(i)].empty()) continue;
        m(i, i) += step;
        for (const int j : rings[std::size_t(i)]) m(i, j) -= step / double(rings[std::size_t(i)].size());
      }
      const Eigen::MatrixXd inverse = m.inverse();
      Eigen::MatrixXd b = Eigen::MatrixXd::Identity(n, n);
      for (int k = 0; k < s.iterations; ++k) b = inverse * b;
      return b;
    };
    const Eigen::MatrixXd b = smoothing(s.step);
    const Eigen::MatrixXd bk = s.translation_blend > 0.0f ? smoothing(s.translation_step) : b;
    Eigen::MatrixXd w = Eigen::MatrixXd::Zero(n, bones);
    for (int k = 0; k < n; ++k) {
      for (int c = 0; c < 4; ++c) w(k, weights.bones[std::size_t(k)][c]) += weights.weights[std::size_t(k)][c];
      w.row(k) /= w.row(k).sum();
      rest.emplace_back(mesh.positions[std::size_t(k)]);
    }
    const auto outer = [](const glm::dvec3& p) {
      const Eigen::Vector4d h(p.x, p.y, p.z, 1.0);
      return Eigen::Matrix4d(h * h.transpose());
    };
    const double alpha = s.translation_blend;
    const double size = glm::length(glm::dvec3(deform::compute_bounds(mesh.positions).max) -
                                    glm::dvec3(deform::compute_bounds(mesh.positions).min));
    omega.assign(std::size_t(n), std::vector<Eigen::Matrix4d>(std::size_t(bones), Eigen::Matrix4d::Zero()));
    for (int i = 0; i < n; ++i) {
      glm::dvec3 centroid(0.0);
      double psi = 0.0;
      for (int k = 0; k < n; ++k) centroid += b(i, k) * rest[std::size_t(k)], psi += b(i, k);
      centroid /= psi;
      Eigen::Matrix4d sum = Eigen::Matrix4d::Zero();
      for (int j = 0; j < bones; ++j) {
        Eigen::Matrix4d& o = omega[std::size_t(i)][std::size_t(j)];
        double smoothed = 0.0;
        for (int k = 0; k < n; ++k) {
          o += b(i, k) * w(k, j) * outer(rest[std::size_t(k)]);
          smoothed += bk(i, k) * w(k, j);
        }
        o = (1.0 - alpha) * o + alpha * smoothed * outer(centroid);
        sum += o;
      }
      const Eigen::Vector3d p = sum.block<3, 1>(0, 3) / sum(3, 3);
      const Eigen::Matrix3d c = sum.block<3, 3>(0, 0) / sum(3, 3) - p * p.transpose();
      const double spread = s.regularization * std::max(c.trace(), 0.0) / 3.0 + 1e-8 * size * size;
      for (int j = 0; j < bones; ++j) {
        Eigen::Matrix4d& o = omega[std::size_t(i)][std::size_t(j)];
        o /= sum(3, 3);
        o.block<3, 3>(0, 0) += spread * o(3, 3) * Eigen::Matrix3d::Identity();
      }
    }
  }

  // Point i under the palette, and its rotation.
  glm::dvec3 deform(std::size_t i, const std::vector<glm::mat4>& palette, glm::dmat3& rotation) const {
    Eigen::Matrix4d q = Eigen::Matrix4d::Zero();
    for (std::size_t j = 0; j < palette.size(); ++j) {
      Eigen::Matrix4d m;
      for (int r = 0; r < 4; ++r)
        for (int c = 0; c < 4; ++c) m(r, c) = double(palette[j][c][r]);
      q += m * omega[i][j];
    }
    q /= q(3, 3);
    const Eigen::Vector3d qc = q.block<3, 1>(0, 3), pr = q.block<1, 3>(3, 0).transpose();
    const Eigen::Matrix3d c = q.block<3, 3>(0, 0) - qc * pr.transpose();
    Eigen::JacobiSVD<Eigen::Matrix3d> svd(c, Eigen::ComputeFullU | Eigen::ComputeFullV);
    Eigen::Matrix3d d = Eigen::Matrix3d::Identity();
    d(2, 2) = (svd.matrixU() * svd.matrixV().transpose()).determinant() < 0.0 ? -1.0 : 1.0;
    const Eigen::Matrix3d r = svd.matrixU() * d * svd.matrixV().transpose();
    const Eigen::Vector3d u(rest[i].x, rest[i].y, rest[i].z);
    const Eigen::Vector3d v = r * u + qc - r * pr;
    for (int a = 0; a < 3; ++a)
      for (int b2 = 0; b2 < 3; ++b2) rotation[b2][a] = r(a, b2);
    return {v.x(), v.y(), v.z()};
  }
};

struct Output {
  std::vector<glm::vec3> positions, normals;
};

Output run(const DirectDeltaMushBinding& b, const std::vector<glm::mat4>& palette, std::span<const glm::vec3> normals) {
  Output out{std::vector<glm::vec3>(b.point_count()), std::vector<glm::vec3>(normals.size())};
  DirectDeltaMushJob job;
  job.binding = &b;
  job.matrices = palette;
  job.out_positions = out.positions;
  job.in_normals = normals;
  job.out_normals = out.normals;
  REQUIRE(job.validate());
  REQUIRE(job.run());
  return out;
}

std::vector<glm::vec3> some_normals(std::size_t n) {
  std::vector<glm::vec3> normals;
  for (std::size_t i = 0; i < n; ++i)
    normals.push_back(glm::normalize(glm::vec3(std::sin(float(i)), std::cos(1.7f * float(i)), 0.3f + float(i % 3))));
  return normals;
}

}  // namespace

TEST_CASE("Direct Delta Mush: the job agrees with the paper's equations in double precision, over seeded poses") {
  const Tube tube = make_tube(14, 10, 3);
  const float size = diagonal(tube.mesh.positions);
  const std::vector<glm::vec3> normals = some_normals(tube.mesh.point_count());
  DirectDeltaMushSettings full;
  full.prune = 0.0f;
  DirectDeltaMushSettings blended = full;
  blended.translation_blend = 0.5f;
  blended.translation_step = 0.7f;
  blended.iterations = 3;
  blended.step = 3.0f;
  DirectDeltaMushSettings bare = full;
  bare.regularization = 0.0f;
  for (const DirectDeltaMushSettings& settings : {full, blended, bare}) {
    CAPTURE(settings.translation_blend);
    CAPTURE(settings.regularization);
    const DirectDeltaMushBinding b = deform::bind_direct_delta_mush(tube.mesh, tube.weights, settings);
    const Reference ref(tube.mesh, tube.weights, tube.bones, settings);
    std::mt19937 random(2019);
    double worst = 0.0, worst_normal = 0.0, moved = 0.0, lbs_gap = 0.0;
    for (int trial = 0; trial < 10; ++trial) {
      const std::vector<glm::mat4> palette =
          chain_palette({random_turn(random, 30.0), random_turn(random, 110.0), random_turn(random, 110.0)}, 4.0f,
                        glm::dvec3(0.3, -0.2, 0.5) * double(trial));
      const Output out = run(b, palette, normals);
      for (std::size_t i = 0; i < out.positions.size(); ++i) {
        glm::dmat3 r;
        const glm::dvec3 expected = ref.deform(i, palette, r);
        worst = std::max(worst, glm::length(glm::dvec3(out.positions[i]) - expected));
        worst_normal = std::max(worst_normal, glm::length(glm::dvec3(out.normals[i]) - r * glm::dvec3(normals[i])));
        moved = std::max(moved, glm::length(expected - glm::dvec3(tube.mesh.positions[i])));
        // Not linear blend skinning under another name: somewhere it differs.
        glm::vec3 lbs(0.0f);
        for (int c = 0; c < 4; ++c)
          lbs += tube.weights.weights[i][c] *
                 glm::vec3(palette[tube.weights.bones[i][c]] * glm::vec4(tube.mesh.positions[i], 1.0f));
        lbs_gap = std::max(lbs_gap, glm::length(expected - glm::dvec3(lbs)));
      }
    }
    MESSAGE("job vs reference: positions within " << worst / size << " of the size, normals within " << worst_normal
                                                  << "; DDM differs from LBS by up to " << lbs_gap / size);
    CHECK(worst <= 2e-5 * size);
    CHECK(worst_normal <= 1e-4);
    CHECK(moved > 0.2 * size);
    CHECK(lbs_gap > 0.01 * size);
  }

  // Pruned (the default) stays close to the unpruned reference: a longer chain, whose far bones reach a point only
  // faintly through the smoothing.
  const Tube chain = make_tube(24, 8, 6);
  const DirectDeltaMushBinding pruned = deform::bind_direct_delta_mush(chain.mesh, chain.weights, {});
  const Reference ref(chain.mesh, chain.weights, chain.bones, full);
  std::mt19937 random(7);
  std::vector<glm::dquat> turns;
  for (int j = 0; j < chain.bones; ++j) turns.push_back(random_turn(random, 40.0));
  const std::vector<glm::mat4> palette = chain_palette(turns, 4.0f, {});
  const Output out = run(pruned, palette, some_normals(chain.mesh.point_count()));
  double worst = 0.0;
  for (std::size_t i = 0; i < out.positions.size(); ++i) {
    glm::dmat3 r;
    worst = std::max(worst, glm::length(glm::dvec3(out.positions[i]) - ref.deform(i, palette, r)));
  }
  MESSAGE("pruned at 1e-3: within " << worst / size << " of the size of the unpruned reference");
  CHECK(worst <= 2e-3 * size);
  const DirectDeltaMushBinding unpruned = deform::bind_direct_delta_mush(chain.mesh, chain.weights, full);
  MESSAGE(pruned.influence_count() << " influences kept of " << unpruned.influence_count());
  CHECK(pruned.influence_count() < unpruned.influence_count());
}

namespace {

// The rest pose on one model: identity matrices, and the palette of the character's own bind pose (T_W · T_B⁻¹ as
// LocalToWorldJob rounds it). Returns the worst distance from the rest, as a fraction of the size.
double rest_error(const deform::Model& model, const DirectDeltaMushSettings& settings, std::size_t* influences) {
  deform::Character c(model);
  REQUIRE(c.update(0.0f));
  const deform::Mesh& mesh = c.model().mesh;
  const float size = diagonal(mesh.positions);
  const DirectDeltaMushBinding b = deform::bind_direct_delta_mush(mesh, c.model().weights, settings);
  if (influences) *influences = b.influence_count();
  const std::vector<glm::mat4> identity(std::max<std::size_t>(b.bone_count, 1), glm::mat4(1.0f));
  const std::vector<glm::mat4> bind(c.palette().begin(), c.palette().end());
  REQUIRE(bind.size() >= b.bone_count);
  const std::vector<glm::vec3> normals = some_normals(mesh.point_count());
  double worst = 0.0;
  for (const std::vector<glm::mat4>* palette : {&identity, &bind}) {
    const Output out = run(b, *palette, normals);
    worst = std::max(worst, max_distance(out.positions, mesh.positions) / size);
    for (std::size_t i = 0; i < normals.size(); ++i) REQUIRE(glm::length(out.normals[i] - normals[i]) < 1e-4f);
  }
  return worst;
}

}  // namespace

TEST_CASE("Direct Delta Mush gives the rest pose back on the built-in character") {
  const deform::Model model = deform::builtin_character();
  DirectDeltaMushSettings wide;
  wide.iterations = 10;
  wide.step = 5.0f;
  DirectDeltaMushSettings split;
  split.translation_blend = 0.8f;
  split.translation_step = 1.0f;
  for (const DirectDeltaMushSettings& settings : {DirectDeltaMushSettings{}, wide, split}) {
    std::size_t influences = 0;
    const double error = rest_error(model, settings, &influences);
    MESSAGE("iterations " << settings.iterations << ", step " << settings.step << ", blend "
                          << settings.translation_blend << ": rest pose within " << error << " of the size; "
                          << influences << " influences for " << model.mesh.point_count() << " points");
    CHECK(error <= 1e-6);
  }
}

#if defined(DEFORM_HAVE_IMPORT)
TEST_CASE("Direct Delta Mush gives the rest pose back on the rigged models of assimp-testmodels") {
  // Where libigl's implementation moves points at rest on about half the models tried (its issue 2346).
  const std::string dir = "/usr/share/assimp/models/";
  for (const char* path :
       {"IQM/mrfixit.iqm", "X/BCN_Epileptic.X", "X/Testwuson.X", "X/anim_test.x", "FBX/animation_with_skeleton.fbx",
        "FBX/huesitos.fbx", "Collada/box_nested_animation.dae", "glTF2/simple_skin/simple_skin.gltf"}) {
    CAPTURE(path);
    REQUIRE_MESSAGE(std::filesystem::exists(dir + path), path << " is missing: install Debian's assimp-testmodels");
    deform::ImportedModel imported = deform::import_model(dir + path);
    REQUIRE(imported.rigged);
    std::size_t influences = 0;
    const double error = rest_error(imported.model, {}, &influences);
    MESSAGE(std::string(path) << ": rest pose within " << error << " of the size; " << imported.model.mesh.point_count()
                              << " points, " << influences << " influences");
    CHECK(error <= 1e-6);
  }
}
#endif

TEST_CASE("Direct Delta Mush: a rigid motion of the whole skeleton moves every point rigidly; normals stay unit") {
  deform::Character c(deform::builtin_character());
  const deform::Mesh& mesh = c.model().mesh;
  const float size = diagonal(mesh.positions);
  const DirectDeltaMushBinding b = deform::bind_direct_delta_mush(mesh, c.model().weights);
  const std::vector<glm::vec3> normals = some_normals(mesh.point_count());
  std::mt19937 random(11);
  for (int trial = 0; trial < 4; ++trial) {
    const glm::dquat q = random_turn(random, 179.0);
    const glm::dvec3 shift(1.5 * trial, -0.5, 3.0);
    const glm::dmat4 g = glm::translate(glm::dmat4(1.0), shift) * glm::mat4_cast(q);
    // The bind pose's palette, then the whole skeleton moved: G · T_W · T_B⁻¹.
    REQUIRE(c.update(0.0f));
    std::vector<glm::mat4> palette;
    for (const glm::mat4& m : c.palette()) palette.push_back(glm::mat4(g * glm::dmat4(m)));
    const Output out = run(b, palette, normals);
    double worst = 0.0, worst_normal = 0.0, worst_unit = 0.0;
    for (std::size_t i = 0; i < out.positions.size(); ++i) {
      worst = std::max(worst,
                       glm::length(glm::dvec3(out.positions[i]) - glm::dvec3(g * glm::dvec4(mesh.positions[i], 1.0))));
      worst_normal = std::max(worst_normal, glm::length(glm::dvec3(out.normals[i]) - q * glm::dvec3(normals[i])));
      worst_unit = std::max(worst_unit, std::abs(double(glm::length(out.normals[i])) - 1.0));
    }
    MESSAGE("rigid motion: points within " << worst / size << " of the size, normals within " << worst_normal);
    CHECK(worst <= 2e-6 * size);
    CHECK(worst_normal <= 1e-5);
    CHECK(worst_unit <= 1e-6);
  }
}

TEST_CASE("Direct Delta Mush: isolated points, zero weights and non-manifold meshes bind; hostile input is refused") {
  Tube tube = make_tube(6, 8, 2);
  deform::Mesh& mesh = tube.mesh;
  // A lone point, a lone triangle, and a fin sharing one edge of the tube with a third triangle (non-manifold).
  const std::uint32_t n = std::uint32_t(mesh.positions.size());
  mesh.positions.insert(
      mesh.positions.end(),
      {{3.0f, 1.0f, 0.0f}, {-3.0f, 1.0f, 0.0f}, {-3.0f, 1.2f, 0.0f}, {-3.0f, 1.0f, 0.2f}, {0.0f, 2.0f, 2.0f}});
  for (std::uint32_t i = n; i < n + 5; ++i) mesh.vertex_point.push_back(i);
  mesh.triangles.insert(mesh.triangles.end(), {n + 1, n + 2, n + 3, 1, 2, n + 4});
  const std::uint16_t one = 1, zero = 0;
  const float full = 1.0f;
  for (int k = 0; k < 5; ++k) deform::append_influences(tube.weights, {k % 2 ? &zero : &one, 1}, {&full, 1});
  // A point of the tube with zero weight: it takes its neighbours'.
  tube.weights.weights[5] = glm::vec4(0.0f);
  const DirectDeltaMushBinding b = deform::bind_direct_delta_mush(mesh, tube.weights);
  const float size = diagonal(mesh.positions);
  const std::vector<glm::mat4> identity(2, glm::mat4(1.0f));
  CHECK(max_distance(run(b, identity, {}).positions, mesh.positions) <= 1e-6 * size);
  // Rigid per bone: the lone point goes with its bone.
  std::vector<glm::mat4> palette =
      chain_palette({glm::dquat(1, 0, 0, 0), glm::angleAxis(1.0, glm::dvec3(0, 0, 1))}, 4.0f, {});
  const Output out = run(b, palette, {});
  CHECK(glm::length(out.positions[n] - glm::vec3(palette[1] * glm::vec4(mesh.positions[n], 1.0f))) < 1e-5f);
  // A point without influences last in the binding, in a block with points that have them: it stays at its rest
  // point, and the kernel reads no influence past the last (ASan sees one: the arrays are shrunk to fit).
  DirectDeltaMushBinding last = b;
  last.rest.push_back({7.0f, 0.0f, 0.0f});
  last.offsets.push_back(last.offsets.back());
  last.bones.shrink_to_fit();
  last.moments.shrink_to_fit();
  DirectDeltaMushJob stale;
  stale.binding = &last;
  CHECK(std::string(stale.run().reason()) == "binding is malformed: lanes not packed from its rows");  // pack again
  REQUIRE(deform::pack_direct_delta_mush(last));
  REQUIRE(last.point_count() % 16 != 1);  // not alone in its block of 16 (the kernel's)
  const Output with_last = run(last, palette, {});
  CHECK(with_last.positions.back() == glm::vec3(7.0f, 0.0f, 0.0f));
  CHECK(std::memcmp(with_last.positions.data(), out.positions.data(), out.positions.size() * sizeof(glm::vec3)) == 0);

  const auto refused = [&](const deform::Mesh& m, const deform::SkinWeights& w, const DirectDeltaMushSettings& s,
                           const char* part) {
    try {
      (void)deform::bind_direct_delta_mush(m, w, s);
      FAIL("accepted");
    } catch (const deform::Error& e) {
      CHECK(e.kind() == deform::Error::Kind::argument);
      CHECK_MESSAGE(std::string(e.what()).find(part) != std::string::npos, e.what());
    }
  };
  DirectDeltaMushSettings s;
  s.iterations = 0;
  refused(mesh, tube.weights, s, "iterations must be within [1, 100]");
  s = {};
  s.step = std::nanf("");
  refused(mesh, tube.weights, s, "step must be positive and finite");
  s = {};
  s.translation_blend = 1.0f;
  refused(mesh, tube.weights, s, "translation_blend must be within [0, 1)");
  s = {};
  s.regularization = -0.5f;
  refused(mesh, tube.weights, s, "regularization must be within [0, 1]");
  s = {};
  s.prune = 0.5f;
  refused(mesh, tube.weights, s, "prune must be within [0, 0.5)");
  deform::SkinWeights w = tube.weights;
  w.weights.pop_back(), w.bones.pop_back();
  refused(mesh, w, {}, "weights have");
  w = tube.weights;
  w.weights[3].y = -1.0f;
  refused(mesh, w, {}, "point 3: weight is not finite and >= 0");
  w = tube.weights;
  w.weights[n] = glm::vec4(0.0f);  // the lone point, nothing connected to it weighted
  refused(mesh, w, {}, "no bone influences it or any point connected to it");
  deform::Mesh broken = mesh;
  broken.positions[4].z = std::numeric_limits<float>::infinity();
  refused(broken, tube.weights, {}, "point 4: rest position is not finite");
  broken = mesh;
  broken.triangles[2] = 1u << 30;
  CHECK_THROWS_AS((void)deform::bind_direct_delta_mush(broken, tube.weights), deform::Error);
  broken = mesh;
  for (glm::vec3& p : broken.positions) p *= 1e25f;  // finite points, squares beyond float
  refused(broken, tube.weights, {}, "its moments overflow float");

  // The job: wrong spans and a malformed binding refused with a reason, nothing written.
  std::vector<glm::vec3> positions(b.point_count(), glm::vec3(7.0f));
  DirectDeltaMushJob job;
  job.binding = &b;
  job.matrices = identity;
  job.out_positions = positions;
  REQUIRE(job.validate());
  const auto refuses = [&](const DirectDeltaMushJob& j, const char* reason, bool o1 = true) {
    CHECK(std::string(j.validate().reason()) == reason);
    if (o1) CHECK(std::string(j.run().reason()) == reason);
    CHECK(positions[0] == glm::vec3(7.0f));
  };
  DirectDeltaMushJob j = job;
  j.binding = nullptr;
  refuses(j, "no binding");
  j = job;
  j.matrices = std::span<const glm::mat4>(identity).first(1);
  refuses(j, "palette is too small");
  j = job;
  j.out_positions = std::span<glm::vec3>(positions).first(3);
  refuses(j, "positions are not one per point");
  std::vector<glm::vec3> few(3);
  j = job;
  j.in_normals = few;
  j.out_normals = few;
  refuses(j, "normals are not one per point");
  std::vector<glm::mat4> bad = identity;
  bad[1][3][0] = std::nanf("");
  j = job;
  j.matrices = bad;
  refuses(j, "palette matrix is not finite", false);
  DirectDeltaMushBinding malformed = b;
  malformed.bones[2] = 9;
  j = job;
  j.binding = &malformed;
  refuses(j, "binding is malformed: bone out of range", false);
  malformed = b;
  malformed.moments[4].yz = std::numeric_limits<float>::infinity();
  refuses(j, "binding is not finite", false);
  malformed = b;
  malformed.moments.pop_back();
  refuses(j, "binding is malformed: arrays differ in size");
  CHECK(std::string(deform::pack_direct_delta_mush(malformed).reason()) ==
        "binding is malformed: arrays differ in size");
  CHECK(malformed.lanes.rounds.empty());
  // Lanes that are not the rows' as they are now: validate() compares them (run() only their sizes).
  malformed = b;
  malformed.lanes = {};
  refuses(j, "binding is malformed: lanes not packed from its rows");
  malformed = b;
  malformed.moments[4].yz += 1.0f;
  refuses(j, "binding is malformed: lanes not packed from its rows", false);
  REQUIRE(deform::pack_direct_delta_mush(malformed));
  CHECK(j.validate());
  malformed = b;
  malformed.bones[0] = std::uint16_t(malformed.bones[0] == 0 ? 1 : 0);  // another bone in range
  refuses(j, "binding is malformed: lanes not packed from its rows", false);
  malformed = b;
  std::swap(malformed.lanes.influence[0], malformed.lanes.influence[1]);  // two lanes' slots crossed
  refuses(j, "binding is malformed: lanes not packed from its rows", false);
  // No points: a binding the job runs (nothing to do).
  const DirectDeltaMushBinding nothing = deform::bind_direct_delta_mush(deform::Mesh{}, deform::SkinWeights{});
  DirectDeltaMushJob none;
  none.binding = &nothing;
  CHECK(none.validate());
  CHECK(none.run());
  CHECK(std::string(job.run(4, 3).reason()) == "range outside the job");
  CHECK(std::string(job.run(0, b.point_count() + 1).reason()) == "range outside the job");
}

TEST_CASE("Direct Delta Mush: ranges and threads give the same bits; no allocation per frame") {
  deform::Character c(deform::builtin_character());
  const deform::Mesh& mesh = c.model().mesh;
  const DirectDeltaMushBinding b = deform::bind_direct_delta_mush(mesh, c.model().weights);
  const deform::Skeleton& sk = c.skeleton();
  deform::Pose pose = sk.bind_pose();
  sk.set_euler(pose, sk.find("forearm_l"), {120.0f, 0.0f, 0.0f});
  sk.set_euler(pose, sk.find("upperarm_l"), {0.0f, 30.0f, 40.0f});
  REQUIRE(c.set_pose(pose));
  REQUIRE(c.update(0.0f));
  const std::vector<glm::mat4> palette(c.palette().begin(), c.palette().end());
  const std::vector<glm::vec3> normals = some_normals(mesh.point_count());
  const Output whole = run(b, palette, normals);
  CHECK(max_distance(whole.positions, mesh.positions) > 0.05 * diagonal(mesh.positions));  // the arm moved
  // The kernel's layout of this binding has both kinds of rounds (a bone shared by a block's lanes, a bone per lane),
  // so that this test runs both; most are shared.
  std::size_t shared = 0;
  for (const std::uint32_t s : b.lanes.shared) shared += s;
  CHECK(shared > b.lanes.rounds.back() / 2);
  CHECK(shared < b.lanes.rounds.back());

  std::vector<glm::vec3> out(mesh.point_count()), out_normals(mesh.point_count());
  std::vector<glm::quat> rotations(mesh.point_count());
  DirectDeltaMushJob job;
  job.binding = &b;
  job.matrices = palette;
  job.out_positions = out;
  job.in_normals = normals;
  job.out_normals = out_normals;
  job.out_rotations = rotations;
  REQUIRE(job.validate());
  for (std::size_t end = job.count(); end > 0;) {
    const std::size_t begin = end > 37 ? end - 37 : 0;
    REQUIRE(job.run(begin, end));
    end = begin;
  }
  CHECK(std::memcmp(out.data(), whole.positions.data(), out.size() * sizeof(glm::vec3)) == 0);
  CHECK(std::memcmp(out_normals.data(), whole.normals.data(), out.size() * sizeof(glm::vec3)) == 0);
  for (std::size_t i = 0; i < out.size(); i += 97)
    CHECK(glm::length(rotations[i] * normals[i] - whole.normals[i]) < 1e-5f);

  deform::ThreadPool pool(3);
  std::fill(out.begin(), out.end(), glm::vec3(0.0f));
  const long before = allocations.load();
  for (int frame = 0; frame < 50; ++frame) {
    REQUIRE(job.run(pool, 64));
    REQUIRE(job.run());
  }
  CHECK(allocations.load() == before);
  CHECK(std::memcmp(out.data(), whole.positions.data(), out.size() * sizeof(glm::vec3)) == 0);

  // Input points: the rest gives the same as none; an offset turns with the point.
  std::vector<glm::vec3> in = mesh.positions, shifted(mesh.point_count());
  in[10] += glm::vec3(0.0f, 0.01f, 0.0f);
  job.in_positions = in;
  job.out_positions = shifted;
  REQUIRE(job.run());
  CHECK(glm::length(shifted[10] - (whole.positions[10] + rotations[10] * glm::vec3(0.0f, 0.01f, 0.0f))) < 1e-6f);
  CHECK(shifted[11] == whole.positions[11]);
}

TEST_CASE("Direct Delta Mush: every instruction set's copy of the kernel agrees with the default; others refuse") {
  deform::Character c(deform::builtin_character());
  const deform::Mesh& mesh = c.model().mesh;
  const DirectDeltaMushBinding b = deform::bind_direct_delta_mush(mesh, c.model().weights);
  const deform::Skeleton& sk = c.skeleton();
  deform::Pose pose = sk.bind_pose();
  sk.set_euler(pose, sk.find("forearm_l"), {120.0f, 0.0f, 0.0f});
  sk.set_euler(pose, sk.find("upperarm_l"), {0.0f, 30.0f, 40.0f});
  REQUIRE(c.set_pose(pose));
  REQUIRE(c.update(0.0f));
  const std::vector<glm::mat4> palette(c.palette().begin(), c.palette().end());
  const std::vector<glm::vec3> normals = some_normals(mesh.point_count());
  const Output best = run(b, palette, normals);  // Isa::automatic, checked against the reference above
  const double size = diagonal(mesh.positions);
  int ran = 0;
  for (const deform::Isa isa :
       {deform::Isa::portable, deform::Isa::avx2, deform::Isa::avx512, deform::Isa::neon, deform::Isa::simd128}) {
    CAPTURE(deform::isa_name(isa));
    std::vector<glm::vec3> out(mesh.point_count()), out_normals(mesh.point_count()), pieces(mesh.point_count());
    DirectDeltaMushJob job;
    job.binding = &b;
    job.matrices = palette;
    job.out_positions = out;
    job.in_normals = normals;
    job.out_normals = out_normals;
    job.isa = isa;
    if (!deform::isa_available(isa)) {
      CHECK(std::string(job.validate().reason()) == "instruction set not available");
      CHECK(std::string(job.run().reason()) == "instruction set not available");
      continue;
    }
    ++ran;
    REQUIRE(job.validate());
    REQUIRE(job.run());
    CHECK(max_distance(out, best.positions) <= 2e-6 * size);
    double worst_normal = 0.0;
    for (std::size_t i = 0; i < out.size(); ++i)
      worst_normal = std::max(worst_normal, double(glm::length(out_normals[i] - best.normals[i])));
    CHECK(worst_normal <= 1e-5);
    // Within one copy, a point's bits do not depend on the range (ranges of 37 cut its blocks of 16 elsewhere).
    job.out_positions = pieces;
    for (std::size_t begin = 0; begin < job.count(); begin += 37)
      REQUIRE(job.run(begin, std::min(job.count(), begin + 37)));
    CHECK(std::memcmp(pieces.data(), out.data(), out.size() * sizeof(glm::vec3)) == 0);
  }
  CHECK(ran >= 1);  // portable at least
}

TEST_CASE("nearest_rotation: the rotation of the SVD, reflections made proper, from a start within 90 degrees") {
  // C = U diag(s) Vᵀ with singular values apart enough for one answer; U and V proper or not (a reflection).
  std::mt19937 random(5);
  std::uniform_real_distribution<double> value(0.2, 1.0);
  const auto rotation = [&](bool mirror) {
    const glm::dmat3 r = glm::mat3_cast(random_turn(random, 180.0));
    Eigen::Matrix3d m;
    for (int a = 0; a < 3; ++a)
      for (int b = 0; b < 3; ++b) m(a, b) = r[b][a] * (mirror && b == 2 ? -1.0 : 1.0);
    return m;
  };
  double worst = 0.0;
  for (int trial = 0; trial < 200; ++trial) {
    double s1 = value(random), s2 = value(random), s3 = value(random);
    if (s2 > s1) std::swap(s1, s2);
    s3 = std::min(s3, 0.5 * s2);
    const Eigen::Matrix3d c = rotation(trial % 3 == 0) * Eigen::Vector3d(s1, s2, s3).asDiagonal() * rotation(false);
    Eigen::JacobiSVD<Eigen::Matrix3d> svd(c, Eigen::ComputeFullU | Eigen::ComputeFullV);
    Eigen::Matrix3d d = Eigen::Matrix3d::Identity();
    d(2, 2) = (svd.matrixU() * svd.matrixV().transpose()).determinant() < 0.0 ? -1.0 : 1.0;
    const Eigen::Matrix3d expected = svd.matrixU() * d * svd.matrixV().transpose();
    glm::mat3 g;
    for (int r = 0; r < 3; ++r)
      for (int k = 0; k < 3; ++k) g[k][r] = float(c(r, k));
    glm::dmat3 answer;
    for (int r = 0; r < 3; ++r)
      for (int k = 0; k < 3; ++k) answer[k][r] = expected(r, k);
    const glm::dquat start = glm::quat_cast(answer) * random_turn(random, 90.0);
    const glm::mat3 got = glm::mat3_cast(deform::nearest_rotation(g, glm::quat(start)));
    for (int r = 0; r < 3; ++r)
      for (int k = 0; k < 3; ++k) worst = std::max(worst, std::abs(double(got[k][r]) - expected(r, k)));
  }
  MESSAGE("nearest_rotation vs SVD: within " << worst);
  CHECK(worst < 1e-4);
}

// --- the reduced form (reduce_direct_delta_mush, DirectDeltaMushReducedJob): ψ and first moments per influence, the
// rotation blended from the bones' quaternions ---

namespace {

using deform::DirectDeltaMushReducedBinding;
using deform::DirectDeltaMushReducedJob;

DirectDeltaMushReducedBinding reduced(const DirectDeltaMushBinding& full) {
  DirectDeltaMushReducedBinding r;
  REQUIRE(deform::reduce_direct_delta_mush(full, r));
  return r;
}

std::vector<deform::DualQuat> rotations_of(const std::vector<glm::mat4>& palette) {
  std::vector<deform::DualQuat> dq(palette.size());
  std::vector<glm::mat3> scales(palette.size());
  bool has_scale = false;
  REQUIRE(deform::compute_dual_quat_palette(palette, dq, scales, has_scale));
  return dq;
}

Output run_reduced(const DirectDeltaMushReducedBinding& b, const std::vector<glm::mat4>& palette,
                   const std::vector<deform::DualQuat>& dq, std::span<const glm::vec3> normals) {
  Output out{std::vector<glm::vec3>(b.point_count()), std::vector<glm::vec3>(normals.size())};
  DirectDeltaMushReducedJob job;
  job.binding = &b;
  job.matrices = palette;
  job.dual_quats = dq;
  job.out_positions = out.positions;
  job.in_normals = normals;
  job.out_normals = out.normals;
  REQUIRE(job.validate());
  REQUIRE(job.run());
  return out;
}

// The rest pose of the reduced form: identity and bind palettes, the worst distance as a fraction of the size.
double reduced_rest_error(const deform::Model& model) {
  deform::Character c(model);
  REQUIRE(c.update(0.0f));
  const deform::Mesh& mesh = c.model().mesh;
  const float size = diagonal(mesh.positions);
  const DirectDeltaMushReducedBinding b = reduced(deform::bind_direct_delta_mush(mesh, c.model().weights));
  const std::vector<glm::mat4> identity(std::max<std::size_t>(b.bone_count, 1), glm::mat4(1.0f));
  const std::vector<glm::mat4> bind(c.palette().begin(), c.palette().end());
  const std::vector<glm::vec3> normals = some_normals(mesh.point_count());
  double worst = 0.0;
  for (const std::vector<glm::mat4>* palette : {&identity, &bind}) {
    const Output out = run_reduced(b, *palette, rotations_of(*palette), normals);
    worst = std::max(worst, max_distance(out.positions, mesh.positions) / size);
    for (std::size_t i = 0; i < normals.size(); ++i) REQUIRE(glm::length(out.normals[i] - normals[i]) < 1e-4f);
  }
  return worst;
}

double signed_volume(const deform::Mesh& mesh, std::span<const glm::vec3> points) {
  double v = 0.0;
  for (std::size_t t = 0; t < mesh.triangle_count(); ++t) {
    const glm::dvec3 a(points[mesh.vertex_point[mesh.triangles[3 * t]]]);
    const glm::dvec3 b(points[mesh.vertex_point[mesh.triangles[3 * t + 1]]]);
    const glm::dvec3 c(points[mesh.vertex_point[mesh.triangles[3 * t + 2]]]);
    v += glm::dot(a, glm::cross(b, c)) / 6.0;
  }
  return v;
}

}  // namespace

TEST_CASE("Reduced Direct Delta Mush: the job agrees with its equations in double precision over 2,000 poses") {
  // The built-in character; each pose a random rigid motion of the whole body, each bone turned by up to 80° about a
  // random pivot and scaled uniformly by 0.8 to 1.25, and each bone's quaternion given a random sign (which the
  // kernel must align as the reference does). The reference: the full binding's moments in double, normalised per
  // point; Rᵢ = normalise(Σ ψ sⱼ qⱼ) with the generating quaternions; tᵢ = Σ (Aⱼ p̃ⱼ + ψ tⱼ) − Rᵢ Σ p̃ⱼ in model
  // coordinates (p̃ absolute: no relative trick); out = Rᵢ rᵢ + tᵢ; normals Rᵢ nᵢ.
  deform::Character c(deform::builtin_character());
  const deform::Mesh& mesh = c.model().mesh;
  const float size = diagonal(mesh.positions);
  const DirectDeltaMushBinding full = deform::bind_direct_delta_mush(mesh, c.model().weights);
  const DirectDeltaMushReducedBinding b = reduced(full);
  const std::vector<glm::vec3> normals = some_normals(mesh.point_count());
  const std::size_t bones = std::max<std::size_t>(b.bone_count, 1);
  std::mt19937 random(33);
  std::uniform_real_distribution<double> unit(-1.0, 1.0), scale(0.8, 1.25);
  std::bernoulli_distribution flip(0.5);
  std::vector<glm::mat4> palette(bones, glm::mat4(1.0f));
  std::vector<glm::dquat> turns(bones);
  std::vector<deform::DualQuat> dq = rotations_of(palette);
  Output out{std::vector<glm::vec3>(b.point_count()), std::vector<glm::vec3>(b.point_count())};
  DirectDeltaMushReducedJob job;
  job.binding = &b;
  job.matrices = palette;
  job.dual_quats = dq;
  job.out_positions = out.positions;
  job.in_normals = normals;
  job.out_normals = out.normals;
  REQUIRE(job.validate());
  double worst = 0.0, worst_normal = 0.0, moved = 0.0;
  for (int pose = 0; pose < 2000; ++pose) {
    const glm::dquat g = random_turn(random, 180.0);
    const glm::dvec3 shift{unit(random), unit(random), unit(random)};
    for (std::size_t j = 0; j < bones; ++j) {
      turns[j] = g * random_turn(random, 80.0);
      if (flip(random)) turns[j] = -turns[j];
      const glm::dvec3 pivot = glm::dvec3{unit(random), unit(random), unit(random)} * double(size) * 0.5;
      const glm::dmat4 m = glm::translate(glm::dmat4(1.0), shift + pivot) * glm::mat4_cast(turns[j]) *
                           glm::scale(glm::dmat4(1.0), glm::dvec3(scale(random))) *
                           glm::translate(glm::dmat4(1.0), -pivot);
      palette[j] = glm::mat4(m);
    }
    dq = rotations_of(palette);
    // The same rotations with the generating signs.
    for (std::size_t j = 0; j < bones; ++j)
      if (glm::dot(glm::dquat(dq[j].real), turns[j]) < 0.0) dq[j].real = -dq[j].real;
    // Each pose runs a window of 256 points (run(begin, end)), the windows walking round the mesh: every point
    // meets about 180 poses, and the test stays short under the sanitizers.
    const std::size_t begin = std::size_t(pose) * 256 % b.point_count(), end = std::min(b.point_count(), begin + 256);
    job.matrices = palette, job.dual_quats = dq;
    REQUIRE(job.run(begin, end));
    for (std::size_t i = begin; i < end; ++i) {
      double psi_sum = 0.0;
      for (std::uint32_t e = full.offsets[i]; e < full.offsets[i + 1]; ++e) psi_sum += full.moments[e].w;
      const glm::dvec3 r(mesh.positions[i]);
      const glm::dquat q0 = turns[full.bones[full.offsets[i]]];
      glm::dquat q(0.0, 0.0, 0.0, 0.0);
      glm::dvec3 sum(0.0), p(0.0);
      for (std::uint32_t e = full.offsets[i]; e < full.offsets[i + 1]; ++e) {
        const deform::DirectDeltaMushMoments& m = full.moments[e];
        const double psi = m.w / psi_sum;
        const glm::dvec3 pt = glm::dvec3(m.x, m.y, m.z) / psi_sum + psi * r;  // absolute: p̃ = p̃ʳ + ψ r
        const glm::dmat4 a(palette[full.bones[e]]);
        const glm::dquat qj = turns[full.bones[e]];
        sum += glm::dmat3(a) * pt + psi * glm::dvec3(a[3]);
        p += pt;
        const double s = glm::dot(qj, q0) < 0.0 ? -psi : psi;
        q.x += s * qj.x, q.y += s * qj.y, q.z += s * qj.z, q.w += s * qj.w;
      }
      q = glm::normalize(q);
      const glm::dvec3 expected = q * r + (sum - q * p);
      worst = std::max(worst, glm::length(glm::dvec3(out.positions[i]) - expected));
      worst_normal = std::max(worst_normal, glm::length(glm::dvec3(out.normals[i]) - q * glm::dvec3(normals[i])));
      moved = std::max(moved, glm::length(expected - r));
    }
  }
  MESSAGE("reduced job vs its double reference over 2,000 poses: positions within "
          << worst / size << " of the size, normals within " << worst_normal);
  CHECK(worst <= 1e-5 * size);
  CHECK(worst_normal <= 1e-5);
  CHECK(moved > 0.2 * size);
}

TEST_CASE("Reduced Direct Delta Mush gives the rest pose back on the built-in character and assimp-testmodels") {
  const double builtin = reduced_rest_error(deform::builtin_character());
  MESSAGE("built-in character: rest pose within " << builtin << " of the size");
  CHECK(builtin <= 1e-6);
#if defined(DEFORM_HAVE_IMPORT)
  const std::string dir = "/usr/share/assimp/models/";
  for (const char* path :
       {"IQM/mrfixit.iqm", "X/BCN_Epileptic.X", "X/Testwuson.X", "X/anim_test.x", "FBX/animation_with_skeleton.fbx",
        "FBX/huesitos.fbx", "Collada/box_nested_animation.dae", "glTF2/simple_skin/simple_skin.gltf"}) {
    CAPTURE(path);
    REQUIRE_MESSAGE(std::filesystem::exists(dir + path), path << " is missing: install Debian's assimp-testmodels");
    const double error = reduced_rest_error(deform::import_model(dir + path).model);
    MESSAGE(std::string(path) << ": reduced rest pose within " << error << " of the size");
    CHECK(error <= 1e-6);
  }
#endif
}

TEST_CASE("Reduced Direct Delta Mush: fewer bytes an influence; near the full form at 150°; no candy wrapper") {
  deform::Character lbs(deform::builtin_character());
  const deform::Model& model = lbs.model();
  const DirectDeltaMushBinding full = deform::bind_direct_delta_mush(model.mesh, model.weights);
  const DirectDeltaMushReducedBinding b = reduced(full);
  // Storage: every array of each form, per influence.
  const auto bytes = [](const auto& v) { return double(v.size() * sizeof(v[0])); };
  const double full_bytes = bytes(full.rest) + bytes(full.offsets) + bytes(full.bones) + bytes(full.moments) +
                            bytes(full.lanes.rounds) + bytes(full.lanes.shared) + bytes(full.lanes.start) +
                            bytes(full.lanes.influence) + bytes(full.lanes.bones) + bytes(full.lanes.moments);
  const double reduced_bytes = bytes(b.rest) + bytes(b.offsets) + bytes(b.bones) + bytes(b.moments) +
                               bytes(b.lanes.rounds) + bytes(b.lanes.shared) + bytes(b.lanes.start) +
                               bytes(b.lanes.influence) + bytes(b.lanes.bones) + bytes(b.lanes.moments);
  const double influences = double(full.influence_count());
  MESSAGE("bytes an influence: full " << full_bytes / influences << " (moments " << bytes(full.moments) / influences
                                      << " + lanes), reduced " << reduced_bytes / influences << " (moments "
                                      << bytes(b.moments) / influences << " + lanes)");
  CHECK(b.influence_count() == full.influence_count());
  // Both forms' kernels read their moments from lanes, which copy them (the reduced form's 4 floats a slot, the full
  // form's 10): in all, the reduced form takes under half the bytes; its moments, under 1 / 2.5.
  CHECK(reduced_bytes * 2.0 <= full_bytes);
  CHECK(bytes(b.moments) * 2.5 <= bytes(full.moments));

  // The left elbow bent 150°: the reduced form close to the full one. Both lose more of the body's volume than LBS
  // there (smoothing cuts the fold's corner: docs/skinning.md), so volume is reported, not required.
  const float size = diagonal(model.mesh.positions);
  deform::Pose pose = lbs.skeleton().bind_pose();
  lbs.skeleton().set_euler(pose, lbs.skeleton().find("forearm_l"), {150.0f, 0.0f, 0.0f}, false);
  REQUIRE(lbs.set_pose(pose));
  REQUIRE(lbs.update(0.0f));
  const std::vector<glm::mat4> palette(lbs.palette().begin(), lbs.palette().end());
  const std::vector<glm::vec3> none;
  const Output v0 = run(full, palette, none);
  const Output v = run_reduced(b, palette, rotations_of(palette), none);
  const double gap = max_distance(v.positions, v0.positions) / size;
  const double rest = signed_volume(model.mesh, model.mesh.positions);
  const double kept_lbs = signed_volume(model.mesh, lbs.positions()) / rest;
  const double kept_full = signed_volume(model.mesh, v0.positions) / rest;
  const double kept_reduced = signed_volume(model.mesh, v.positions) / rest;
  MESSAGE("elbow 150°: reduced within " << 100.0 * gap << "% of the diagonal of the full form; volume kept: LBS "
                                        << 100.0 * kept_lbs << "%, full " << 100.0 * kept_full << "%, reduced "
                                        << 100.0 * kept_reduced << "%");
  CHECK(gap <= 0.03);
  CHECK(gap > 0.0);

  // The candy wrapper (as tests/runtime/skinning_test.cpp measures it): a tube's middle bone twisted 150° about the
  // tube's axis; LBS pinches the twisted rings toward the axis (to |cos 75°| of their radius at the blend's middle).
  // The reduced form pinches less: its rotation is blended, but its smoothed centroids move as LBS moves them.
  const Tube tube = make_tube(20, 12, 3);
  const DirectDeltaMushReducedBinding tb = reduced(deform::bind_direct_delta_mush(tube.mesh, tube.weights));
  const std::vector<glm::mat4> twist =
      chain_palette({glm::dquat(1.0, 0.0, 0.0, 0.0), glm::angleAxis(glm::radians(150.0), glm::dvec3(0.0, 1.0, 0.0)),
                     glm::dquat(1.0, 0.0, 0.0, 0.0)},
                    4.0f, {});
  const Output twisted = run_reduced(tb, twist, rotations_of(twist), none);
  const Output twisted_full = run(deform::bind_direct_delta_mush(tube.mesh, tube.weights), twist, none);
  double lbs_least = 1.0, reduced_least = 1.0, full_least = 1.0;
  for (std::size_t i = 0; i < tube.mesh.point_count(); ++i) {
    const glm::vec3 r = tube.mesh.positions[i];
    const double radius = std::hypot(r.x, r.z);
    if (radius < 0.1) continue;  // the caps' centres
    glm::vec3 l(0.0f);
    for (int k = 0; k < 4; ++k)
      l += tube.weights.weights[i][k] * glm::vec3(twist[tube.weights.bones[i][k]] * glm::vec4(r, 1.0f));
    lbs_least = std::min(lbs_least, std::hypot(double(l.x), double(l.z)) / radius);
    reduced_least =
        std::min(reduced_least, std::hypot(double(twisted.positions[i].x), double(twisted.positions[i].z)) / radius);
    full_least = std::min(
        full_least, std::hypot(double(twisted_full.positions[i].x), double(twisted_full.positions[i].z)) / radius);
  }
  MESSAGE("tube twisted 150°: the thinnest ring point keeps " << 100.0 * lbs_least << "% of its radius under LBS, "
                                                              << 100.0 * reduced_least << "% under the reduced form, "
                                                              << 100.0 * full_least << "% under the full form");
  CHECK(lbs_least < 0.4);
  CHECK(reduced_least > lbs_least + 0.1);
}

TEST_CASE("Reduced Direct Delta Mush: ranges, threads and in-place input give the same bits; hostile input refused") {
  deform::Character c(deform::builtin_character());
  const deform::Mesh& mesh = c.model().mesh;
  DirectDeltaMushReducedBinding b = reduced(deform::bind_direct_delta_mush(mesh, c.model().weights));
  deform::Pose pose = c.skeleton().bind_pose();
  c.skeleton().set_euler(pose, c.skeleton().find("forearm_l"), {110.0f, 0.0f, 0.0f});
  REQUIRE(c.set_pose(pose));
  REQUIRE(c.update(0.0f));
  const std::vector<glm::mat4> palette(c.palette().begin(), c.palette().end());
  const std::vector<deform::DualQuat> dq = rotations_of(palette);
  const std::vector<glm::vec3> normals = some_normals(mesh.point_count());
  const Output whole = run_reduced(b, palette, dq, normals);
  Output parts{std::vector<glm::vec3>(b.point_count()), std::vector<glm::vec3>(b.point_count())};
  std::vector<glm::quat> rotations(b.point_count());
  DirectDeltaMushReducedJob job;
  job.binding = &b, job.matrices = palette, job.dual_quats = dq;
  job.out_positions = parts.positions, job.in_normals = normals, job.out_normals = parts.normals;
  job.out_rotations = rotations;
  REQUIRE(job.validate());
  const long before = allocations.load();
  for (std::size_t begin = 0; begin < b.point_count(); begin += 37)
    REQUIRE(job.run(begin, std::min(b.point_count(), begin + 37)));
  CHECK(allocations.load() == before);
  CHECK(std::memcmp(parts.positions.data(), whole.positions.data(), parts.positions.size() * 12) == 0);
  CHECK(std::memcmp(parts.normals.data(), whole.normals.data(), parts.normals.size() * 12) == 0);
  deform::ThreadPool pool(2);
  std::fill(parts.positions.begin(), parts.positions.end(), glm::vec3(0.0f));
  REQUIRE(job.run(pool, 64));
  CHECK(std::memcmp(parts.positions.data(), whole.positions.data(), parts.positions.size() * 12) == 0);
  // The input points: the rest points given explicitly give the same bits as none.
  job.in_positions = mesh.positions;
  REQUIRE(job.run());
  CHECK(std::memcmp(parts.positions.data(), whole.positions.data(), parts.positions.size() * 12) == 0);
  CHECK(job.run(5, 3).reason() == std::string("range outside the job"));

  // Hostile: each refused by validate() with its reason.
  const auto refused = [&](const DirectDeltaMushReducedJob& j, const char* reason) {
    const deform::Status s = j.validate();
    CHECK(!s);
    CHECK(s.reason() == std::string(reason));
  };
  DirectDeltaMushReducedJob bad = job;
  bad.binding = nullptr;
  refused(bad, "no binding");
  bad = job, bad.dual_quats = std::span<const deform::DualQuat>(dq).first(b.bone_count - 1);
  refused(bad, "palette is too small");
  bad = job, bad.out_positions = std::span<glm::vec3>(parts.positions).first(3);
  refused(bad, "positions are not one per point");
  std::vector<deform::DualQuat> nan_dq = dq;
  nan_dq[b.bones[0]].real.x = std::nanf("");
  bad = job, bad.dual_quats = nan_dq;
  refused(bad, "dual quaternion is not finite");
  const auto edited = [&](auto edit, const char* reason) {
    DirectDeltaMushReducedBinding e = b;
    edit(e);
    DirectDeltaMushReducedJob j = job;
    j.binding = &e;
    refused(j, reason);
  };
  edited([](DirectDeltaMushReducedBinding& e) { e.bones[10] = std::uint16_t(e.bone_count); },
         "binding is malformed: bone out of range");
  edited([](DirectDeltaMushReducedBinding& e) { e.moments[7].y = INFINITY; }, "binding is not finite");
  edited([](DirectDeltaMushReducedBinding& e) { e.moments[e.offsets[3]].w = 0.0f; },
         "binding is malformed: a point's smoothed weights do not sum above 0");
  edited([](DirectDeltaMushReducedBinding& e) { e.moments.pop_back(); }, "binding is malformed: arrays differ in size");
  edited([](DirectDeltaMushReducedBinding& e) { std::swap(e.offsets[4], e.offsets[5]); },
         "binding is malformed: offsets do not ascend from 0");
  // The reduction refuses a malformed full binding, leaving its output empty.
  DirectDeltaMushBinding broken = deform::bind_direct_delta_mush(mesh, c.model().weights);
  broken.offsets.pop_back();
  DirectDeltaMushReducedBinding out = b;
  CHECK(!deform::reduce_direct_delta_mush(broken, out));
  CHECK(out.point_count() == 0);
}

namespace {

// A reduced binding made up: `n` points, each with 0 to 12 influences (bones of 20, a bone now and then twice in a
// row, the largest ψ first, the ψ summing to 1), first moments of a few centimetres, rest points in a metre's box.
DirectDeltaMushReducedBinding random_reduced(std::mt19937& random, std::size_t n) {
  std::uniform_real_distribution<float> unit(-1.0f, 1.0f), positive(0.05f, 1.0f);
  std::uniform_int_distribution<int> bone(0, 19), count(0, 12);
  DirectDeltaMushReducedBinding b;
  b.bone_count = 20;
  b.offsets.push_back(0);
  for (std::size_t i = 0; i < n; ++i) {
    b.rest.push_back({unit(random), unit(random), unit(random)});
    const int k = i == 1 ? 0 : i == 2 ? 12 : count(random);  // an empty row and a long one in any binding of 3 or more
    std::vector<float> psi;
    double sum = 0.0;
    for (int j = 0; j < k; ++j) psi.push_back(positive(random)), sum += psi.back();
    std::sort(psi.begin(), psi.end(), std::greater<>());
    for (int j = 0; j < k; ++j) {
      const int same = j > 0 && bone(random) == 0 ? int(b.bones.back()) : bone(random);
      b.bones.push_back(std::uint16_t(same));
      b.moments.push_back({0.05f * unit(random), 0.05f * unit(random), 0.05f * unit(random), float(psi[j] / sum)});
    }
    b.offsets.push_back(std::uint32_t(b.bones.size()));
  }
  REQUIRE(deform::pack_direct_delta_mush(b));
  return b;
}

// The reduced job's equations (the header) evaluated a point at a time in float, each row in its own order: what the
// job computed before it had lanes, for the comparison below.
Output scalar_reduced(const DirectDeltaMushReducedBinding& b, const std::vector<glm::mat4>& palette,
                      const std::vector<deform::DualQuat>& dq, std::span<const glm::vec3> in,
                      std::span<const glm::vec3> normals) {
  Output out{std::vector<glm::vec3>(b.point_count()), std::vector<glm::vec3>(normals.size())};
  for (std::size_t i = 0; i < b.point_count(); ++i) {
    const glm::vec3 r = b.rest[i], x = in.empty() ? r : in[i];
    glm::mat3 rotation(1.0f);
    glm::vec3 position = x;
    if (b.offsets[i] < b.offsets[i + 1]) {
      const glm::mat4& m0 = palette[b.bones[b.offsets[i]]];
      const glm::quat q0 = dq[b.bones[b.offsets[i]]].real;
      const glm::vec3 c(m0 * glm::vec4(r, 1.0f));
      glm::vec3 blend(0.0f), moved(0.0f), centroid(0.0f);
      glm::vec4 q(0.0f);  // x, y, z, w
      for (std::uint32_t e = b.offsets[i]; e < b.offsets[i + 1]; ++e) {
        const glm::mat4& m = palette[b.bones[e]];
        const glm::quat qj = dq[b.bones[e]].real;
        const glm::vec3 p(b.moments[e]);
        const float psi = b.moments[e].w;
        blend += psi * (glm::vec3(m * glm::vec4(r, 1.0f)) - c);
        moved += glm::mat3(m) * p;
        centroid += p;
        const float w = glm::dot(qj, q0) < 0.0f ? -psi : psi;
        q += w * glm::vec4(qj.x, qj.y, qj.z, qj.w);
      }
      rotation = glm::mat3_cast(glm::normalize(glm::quat(q.w, q.x, q.y, q.z)));
      position = c + (blend + (moved - rotation * centroid) + rotation * (x - r));
    }
    out.positions[i] = position;
    if (!normals.empty()) {
      const glm::vec3 n = rotation * normals[i];
      out.normals[i] = glm::dot(n, n) > 0.0f ? glm::normalize(n) : glm::vec3(0.0f);
    }
  }
  return out;
}

}  // namespace

TEST_CASE("Reduced Direct Delta Mush: every instruction set's copy agrees with the equations point by point") {
  // Made-up bindings of 1 to 101 points (blocks of 16 and a partial one, rows of up to 12 influences, empty ones, a
  // bone twice in a row), random palettes (turns, uniform scales, translations; the quaternions' signs flipped at
  // random), input points and normals: each copy of the kernel against the scalar evaluation, a point's bits the same
  // over any range, and the identity palette giving each rest point back exactly.
  std::mt19937 random(61);
  std::uniform_real_distribution<double> unit(-1.0, 1.0), scale(0.8, 1.25);
  std::bernoulli_distribution flip(0.5);
  int ran = 0;
  for (const std::size_t n : {std::size_t(1), std::size_t(2), std::size_t(15), std::size_t(17), std::size_t(101)}) {
    CAPTURE(n);
    const DirectDeltaMushReducedBinding b = random_reduced(random, n);
    std::vector<glm::mat4> palette(b.bone_count);
    for (glm::mat4& m : palette) {
      const glm::dvec3 shift{unit(random), unit(random), unit(random)};
      const glm::dquat turn = random_turn(random, 120.0);
      const double size = scale(random);
      m = glm::mat4(glm::translate(glm::dmat4(1.0), shift) * glm::mat4_cast(turn) *
                    glm::scale(glm::dmat4(1.0), glm::dvec3(size)));
    }
    std::vector<deform::DualQuat> dq = rotations_of(palette);
    for (deform::DualQuat& d : dq)
      if (flip(random)) d.real = -d.real;
    std::vector<glm::vec3> in(n), normals = some_normals(n);
    for (std::size_t i = 0; i < n; ++i)
      in[i] = b.rest[i] + 0.01f * glm::vec3{float(unit(random)), float(unit(random)), float(unit(random))};
    normals[0] = glm::vec3(0.0f);  // zero stays zero
    const Output expected = scalar_reduced(b, palette, dq, in, normals);
    const std::vector<glm::mat4> identity(b.bone_count, glm::mat4(1.0f));
    const std::vector<deform::DualQuat> identity_dq = rotations_of(identity);
    for (const deform::Isa isa : {deform::Isa::automatic, deform::Isa::portable, deform::Isa::avx2, deform::Isa::avx512,
                                  deform::Isa::neon, deform::Isa::simd128}) {
      CAPTURE(deform::isa_name(isa));
      Output out{std::vector<glm::vec3>(n), std::vector<glm::vec3>(n)}, pieces = out;
      std::vector<glm::quat> rotations(n);
      DirectDeltaMushReducedJob job;
      job.binding = &b, job.matrices = palette, job.dual_quats = dq, job.isa = isa;
      job.in_positions = in, job.out_positions = out.positions;
      job.in_normals = normals, job.out_normals = out.normals, job.out_rotations = rotations;
      if (!deform::isa_available(isa)) {
        CHECK(std::string(job.validate().reason()) == "instruction set not available");
        CHECK(std::string(job.run().reason()) == "instruction set not available");
        continue;
      }
      ++ran;
      REQUIRE(job.validate());
      REQUIRE(job.run());
      double worst = 0.0, worst_normal = 0.0, worst_rotation = 0.0;
      for (std::size_t i = 0; i < n; ++i) {
        worst = std::max(worst, double(glm::length(out.positions[i] - expected.positions[i])));
        worst_normal = std::max(worst_normal, double(glm::length(out.normals[i] - expected.normals[i])));
        worst_rotation =
            std::max(worst_rotation,
                     double(glm::length(rotations[i] * normals[i] - expected.normals[i] * glm::length(normals[i]))));
        if (b.offsets[i] == b.offsets[i + 1]) {  // no influences: the input point, its normal, the identity
          CHECK(out.positions[i] == in[i]);
          CHECK(rotations[i] == glm::quat(1.0f, 0.0f, 0.0f, 0.0f));
        }
      }
      CHECK(worst <= 2e-6);  // the points are within 2 of the origin
      CHECK(worst_normal <= 2e-6);
      CHECK(worst_rotation <= 2e-6);
      CHECK(out.normals[0] == glm::vec3(0.0f));
      // Ranges of 7 cut the blocks of 16 elsewhere: the same bits.
      job.out_positions = pieces.positions, job.out_normals = pieces.normals;
      for (std::size_t begin = 0; begin < n; begin += 7) REQUIRE(job.run(begin, std::min(n, begin + 7)));
      CHECK(std::memcmp(pieces.positions.data(), out.positions.data(), n * sizeof(glm::vec3)) == 0);
      CHECK(std::memcmp(pieces.normals.data(), out.normals.data(), n * sizeof(glm::vec3)) == 0);
      // The identity palette, without input points: each rest point exactly.
      job.matrices = identity, job.dual_quats = identity_dq, job.in_positions = {};
      REQUIRE(job.run());
      CHECK(std::memcmp(pieces.positions.data(), b.rest.data(), n * sizeof(glm::vec3)) == 0);
    }
  }
  CHECK(ran >= 6);  // automatic and portable at least, for each binding
}

TEST_CASE("Reduced Direct Delta Mush: its lanes share bones where they can; rows edited after packing are refused") {
  deform::Character c(deform::builtin_character());
  DirectDeltaMushReducedBinding b = reduced(deform::bind_direct_delta_mush(c.model().mesh, c.model().weights));
  // The built-in character's blocks take most of their rounds with one bone for all their lanes, some not (so that
  // the tests above run both kinds of rounds on it); the lanes copy the 4 floats an influence.
  std::size_t shared = 0;
  for (const std::uint32_t s : b.lanes.shared) shared += s;
  CHECK(shared > b.lanes.rounds.back() / 2);
  CHECK(shared < b.lanes.rounds.back());
  CHECK(b.lanes.moments.size() == std::size_t(b.lanes.rounds.back()) * 16 * 4);
  const std::vector<glm::mat4> palette(c.palette().begin(), c.palette().end());
  const std::vector<deform::DualQuat> dq = rotations_of(palette);
  std::vector<glm::vec3> out(b.point_count());
  DirectDeltaMushReducedJob job;
  job.binding = &b, job.matrices = palette, job.dual_quats = dq, job.out_positions = out;
  REQUIRE(job.validate());
  // A moment edited in the rows: the lanes no longer hold them. Packing again mends it.
  b.moments[5].x += 0.001f;
  CHECK(std::string(job.validate().reason()) == "binding is malformed: lanes not packed from its rows");
  REQUIRE(deform::pack_direct_delta_mush(b));
  CHECK(job.validate());
  // No lanes at all: refused by run() too (its O(1) checks), writing nothing.
  b.lanes = {};
  CHECK(std::string(job.validate().reason()) == "binding is malformed: lanes not packed from its rows");
  CHECK(std::string(job.run().reason()) == "binding is malformed: lanes not packed from its rows");
  // Rows the packer refuses leave the lanes empty.
  b.offsets.pop_back();
  CHECK(std::string(deform::pack_direct_delta_mush(b).reason()) == "binding is malformed: arrays differ in size");
  CHECK(b.lanes.rounds.empty());
}
