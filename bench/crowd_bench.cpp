// crowd/builtin_1000/threads:N — one frame of a crowd: 1,000 instances of the built-in character (Character::instance,
// sharing the bind data), each walking at its own clip time and with its own springs (the left arm's three lattices
// stretched by a different amount per instance and let go and stretched again at different frames), each updated
// as frame/builtin_whole is: walk sampled, set_pose, update, normals() (transported). Before each update the loop
// asks for the next instances' state (Character::prefetch on the next, prefetch_record on the one after), as an
// engine's crowd loop would (docs/performance.md has the effect). The instances are split into N contiguous ranges,
// one per thread, as an engine's job system would (here a ThreadPool; the library runs no threads of its own).
// Counters: bytes_first — heap bytes held by the first character (make_builtin_character);
// bytes_per_instance — held by each further instance (glibc's mallinfo2, live bytes after construction).
//
// crowd/builtin_10000/threads:N/level1_interval:K — one frame of 10,000 instances at levels of detail
// (Character::set_levels), the mix issue #36 states for one camera: 100 at level 0 (the full character), 900 at level
// 1, 4,500 each at levels 2 and 3, interleaved by index (as a camera's distances would be, and so each thread's range
// gets the same mix), all walking at their own clip times, each updated as above (walk sampled, set_pose, update,
// normals()), except that the clip is not sampled for an update that does not deform (Character::next_update_deforms),
// and that the loop reads what a renderer would: interpolation() every update, normals() after the updates that deform.
// Levels 2 and 3 interpolate on the renderer (Settings::renderer_interpolates: an update between their deformed ones
// moves no point; the renderer draws from + share · (to − from)). Each instance takes its level on one of the warm-up's
// first 4 frames (as characters cross a camera's distances on different frames), so the deformed updates of an interval
// spread over its frames rather than all falling on one. The levels, from build_bone_lod on the built-in character's 33
// bones, the hands and feet kept: 1 — 25 bones, deformers on, deformed every Kth update (1: every one; 2: as a
// mid-distance character is in engines' update-rate levels, interpolated on the renderer as levels 2 and 3); 2 — 20
// bones, no deformers, deformed every 2nd update; 3 — 17 bones, no deformers, every 4th. Where the optional
// deform::simplify is built, levels 1, 2 and 3 deform only the points of a simplified mesh (LevelOptions::points
// from simplify_model's source_point: 0.5 of the triangles, that mesh simplified again to 0.5 of its own, 0.25 of the
// whole, and that one to 0.4 of its own, 0.1 of the whole; max_error 0.05), the model's points renumbered so that
// level 3's come first, then level 2's, then level 1's (order_points_first): each level a prefix of the points. Level
// 1 then runs the ponytail's spring chain but not the arm's lattices (a subset runs the springs alone). Without
// deform::simplify every level deforms every point.
// Counters:
// frame_p50_ms, frame_p90_ms — the median and 90th percentile of the frames' wall times (with every level deforming on
// the same frames they were 15–16 and 24–32 ms, for a mean of 15–16: docs/performance.md, 22:40 UTC);
// error_mean_lN, error_max_lN — level N's own points as drawn (interpolation()) against the full character's walking
// beside it (the same clip times, 2 s), as a fraction of its height: the mean over points and frames and the largest;
// points_influences_lN — its LevelCost::influences; points_lN — its LevelCost::points.
#include <benchmark/benchmark.h>

#include <algorithm>
#include <chrono>
#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>
#if defined(__GLIBC__)
#include <malloc.h>
#endif

#include "deform/character/character.hpp"
#include "deform/extras/builtin.hpp"
#include "deform/offline/bone_lod.hpp"
#include "deform/offline/topology.hpp"
#include "deform/runtime/animation.hpp"
#include "deform/runtime/parallel.hpp"
#if defined(DEFORM_BENCH_HAVE_SIMPLIFY)
#include "deform/simplify/simplify.hpp"
#endif
namespace {

constexpr std::size_t crowd_size = 1000;
constexpr float dt = 1.0f / 60.0f;

double heap_bytes() {
#if defined(__GLIBC__)
  return double(mallinfo2().uordblks);
#else
  return 0.0;
#endif
}

struct Crowd {
  std::vector<deform::Character> characters;
  std::vector<deform::Pose> poses;
  std::vector<float> times;
  std::vector<float> stretches;  // each instance's arm stretch (model units) when held
  deform::Animation walk;
  double bytes_first = 0.0;
  double bytes_per_instance = 0.0;
  int frame = 0;

  Crowd() {
    const double before = heap_bytes();
    deform::Character first = deform::make_builtin_character();
    bytes_first = heap_bytes() - before;
    walk = deform::builtin_walk(first.model());
    characters.reserve(crowd_size);
    const double instances_before = heap_bytes();
    for (std::size_t i = 1; i < crowd_size; ++i) characters.push_back(first.instance());
    bytes_per_instance = (heap_bytes() - instances_before) / double(crowd_size - 1);
    characters.push_back(std::move(first));
    poses.assign(crowd_size, characters.front().skeleton().bind_pose());
    for (std::size_t i = 0; i < crowd_size; ++i) {
      times.push_back(0.618034f * float(i));  // spread over the clip
      stretches.push_back(0.05f + 0.25f * float(i % 7) / 6.0f);
    }
  }

  // Instances [begin, end): their targets, then their frame. Touches nothing outside the range.
  void update(std::size_t begin, std::size_t end) {
    deform::SamplingJob sampling;
    sampling.animation = &walk;
    for (std::size_t i = begin; i < end; ++i) {
      deform::Character& c = characters[i];
      // Stretched for 2 s, let go for 2 s, each instance at its own phase.
      const int phase = (frame + int(i * 37)) % 240;
      if (phase == 0 || phase == 120) {
        for (std::size_t l = 0; l < c.deformers().lattice_count(); ++l) {
          c.deformers().set_stretch_target(l, phase == 0 ? stretches[i] * c.deformers().length(l) : 0.0f);
        }
      }
      times[i] += dt;
      sampling.time = times[i];
      sampling.rotations = poses[i].rotations;
      sampling.translations = poses[i].translations;
      sampling.run();
      // The next characters' state on its way while this one computes: the record two ahead, the arrays one ahead.
      if (i + 2 < end) characters[i + 2].prefetch_record();
      if (i + 1 < end) characters[i + 1].prefetch();
      c.set_pose(poses[i]);
      c.update(dt);
      benchmark::DoNotOptimize(c.normals().data());
    }
  }
};

void crowd(benchmark::State& state) {
  Crowd crowd;
  // Every instance's springs under way: two seconds of frames, in which each instance is stretched or let go.
  for (int f = 0; f < 120; ++f, ++crowd.frame) crowd.update(0, crowd_size);
  deform::ThreadPool pool(unsigned(state.range(0)));
  const std::function<void(std::size_t, std::size_t)> range = [&](std::size_t begin, std::size_t end) {
    crowd.update(begin, end);
  };
  for (auto _ : state) {
    pool.parallel_for(crowd_size, 1, range);
    ++crowd.frame;
  }
  state.SetItemsProcessed(state.iterations() * std::int64_t(crowd_size));
  state.counters["bytes_first"] = crowd.bytes_first;
  state.counters["bytes_per_instance"] = crowd.bytes_per_instance;
}

BENCHMARK(crowd)
    ->Name("crowd/builtin_1000")
    ->ArgName("threads")
    ->Arg(1)
    ->Arg(2)
    ->UseRealTime()
    ->Unit(benchmark::kMillisecond);

constexpr std::size_t big_crowd_size = 10000;

deform::BoneLod crowd_lod(const deform::Character& c) {
  deform::BoneLodSettings settings;
  settings.bones_per_level = {25, 20, 17};
  // The hands and feet kept, with the bones above them: a walk bends the elbows and knees at every level (merged by
  // weight alone, the forearms go before the ponytail, a fifth of the height of error at the hands).
  const deform::Skeleton& skeleton = c.skeleton();
  settings.keep = {skeleton.find("hand_l"), skeleton.find("hand_r"), skeleton.find("foot_l"), skeleton.find("foot_r")};
  return deform::build_bone_lod(c.model(), settings);
}

// The crowd's character and its levels' options: levels 1, 2 and 3 with the points of simplified meshes, nested and
// first in the model's renumbered points (a prefix each), where deform::simplify is built.
deform::Character crowd_character(std::vector<deform::Character::LevelOptions>& levels,
                                  std::vector<std::uint32_t>& points, std::uint32_t level1_interval) {
  levels = {{true, 1}, {true, level1_interval}, {false, 2}, {false, 4}};
#if defined(DEFORM_BENCH_HAVE_SIMPLIFY)
  deform::Model model = deform::builtin_character();
  // Each mesh simplified from the one before: 0.5, 0.25 and 0.1 of the triangles, each one's points the next's too.
  std::vector<deform::MeshLevel> meshes = deform::simplify_levels(
      model, std::vector<deform::SimplifySettings>{{0.5f, 0.05f}, {0.25f, 0.05f}, {0.1f, 0.05f}});
  deform::renumber_levels(meshes, deform::order_points_first(model, meshes.front().points));
  points = meshes.front().points;  // 0, 1, ...: each level's points a prefix
  levels[1].points = points;       // deformers on: the ponytail's spring chain; the arm's lattices wait for level 0
  levels[2].points = std::span<const std::uint32_t>(points).first(meshes[1].points.size());
  levels[3].points = std::span<const std::uint32_t>(points).first(meshes[2].points.size());
  const deform::Rig rig = deform::builtin_rig(model);
  return deform::Character(std::move(model), rig);
#else
  (void)points;
  return deform::make_builtin_character();
#endif
}

// The level of instance i: 1 in 100 at 0, 9 at 1, 45 each at 2 and 3.
std::size_t crowd_level(std::size_t i) {
  const std::size_t k = i % 100;
  return k == 0 ? 0 : k < 10 ? 1 : k < 55 ? 2 : 3;
}

struct LevelError {
  double mean = 0.0;
  double max = 0.0;
};

// Each level against the full character walking beside it, over the level's own points (those it draws): 2 s of
// frames after 1 s to get the springs going.
std::vector<LevelError> level_errors(const deform::Character& first, const deform::Animation& walk,
                                     const std::vector<deform::Character::LevelOptions>& options) {
  const std::vector<glm::vec3>& bind = first.model().mesh.positions;
  float low = bind.front().y, high = bind.front().y;
  for (const glm::vec3& p : bind) low = std::min(low, p.y), high = std::max(high, p.y);
  const double height = double(high - low);
  std::vector<LevelError> errors(first.level_count());
  for (std::size_t l = 1; l < first.level_count(); ++l) {
    deform::Character full = first.instance(), level = first.instance();
    full.set_level(0);
    level.set_level(l);
    deform::Pose pose = first.skeleton().bind_pose();
    deform::SamplingJob sampling;
    sampling.animation = &walk;
    sampling.rotations = pose.rotations;
    sampling.translations = pose.translations;
    const int frames = 180, measured = 120;
    for (int f = 0; f < frames; ++f) {
      sampling.time = float(f) * dt;
      sampling.run();
      full.set_pose(pose);
      level.set_pose(pose);
      full.update(dt);
      level.update(dt);
      if (f < frames - measured) continue;
      const auto a = full.positions();
      const deform::Character::Interpolation b = level.interpolation();
      const std::size_t count = options[l].points.empty() ? a.size() : options[l].points.size();
      for (std::size_t i = 0; i < count; ++i) {
        const std::size_t p = options[l].points.empty() ? i : options[l].points[i];
        const double d = double(glm::length(a[p] - (b.from[p] + b.share * (b.to[p] - b.from[p])))) / height;
        errors[l].mean += d / double(count * std::size_t(measured));
        errors[l].max = std::max(errors[l].max, d);
      }
    }
  }
  return errors;
}

struct LevelCrowd {
  std::vector<deform::Character> characters;
  std::vector<deform::Pose> poses;
  std::vector<float> times;
  deform::Animation walk;
  std::vector<LevelError> errors;
  std::vector<std::size_t> influences;
  std::vector<std::size_t> points;

  explicit LevelCrowd(std::uint32_t level1_interval) {
    std::vector<deform::Character::LevelOptions> options;
    std::vector<std::uint32_t> level_points;
    deform::Character first = crowd_character(options, level_points, level1_interval);
    first.set_levels(crowd_lod(first), options);
    first.settings.renderer_interpolates = true;  // copied by instance()
    walk = deform::builtin_walk(first.model());
    errors = level_errors(first, walk, options);
    for (std::size_t l = 0; l < first.level_count(); ++l) {
      influences.push_back(first.level_cost(l).influences);
      points.push_back(first.level_cost(l).points);
    }
    characters.reserve(big_crowd_size);
    for (std::size_t i = 1; i < big_crowd_size; ++i) characters.push_back(first.instance());
    characters.push_back(std::move(first));
    poses.assign(big_crowd_size, characters.front().skeleton().bind_pose());
    for (std::size_t i = 0; i < big_crowd_size; ++i) times.push_back(0.618034f * float(i));
  }

  // Eight frames on `pool`, as the timed ones run: every level's interval under way, the springs moving, and the
  // pool's threads past their first frame (which took about 4 ordinary ones). Instance i takes its level at frame
  // i % 4: in a game characters cross the distances that choose their levels on different frames, so that the
  // deformed updates of an interval are spread over its frames, not all on one (each frame then costs about the same).
  void warm_up(deform::ThreadPool& pool) {
    for (std::size_t f = 0; f < 8; ++f) {
      for (std::size_t i = 0; i < big_crowd_size; ++i)
        if (i % 4 == f) characters[i].set_level(crowd_level(i));
      pool.parallel_for(big_crowd_size, 1, [this](std::size_t begin, std::size_t end) { update(begin, end); });
    }
  }

  void update(std::size_t begin, std::size_t end) {
    deform::SamplingJob sampling;
    sampling.animation = &walk;
    for (std::size_t i = begin; i < end; ++i) {
      deform::Character& c = characters[i];
      times[i] += dt;
      if (i + 2 < end) characters[i + 2].prefetch_record();
      if (i + 1 < end) characters[i + 1].prefetch();
      // An update between a level's deformed ones reads no pose: the clip is not sampled for it.
      const bool deforms = c.next_update_deforms();
      if (deforms) {
        sampling.time = times[i];
        sampling.rotations = poses[i].rotations;
        sampling.translations = poses[i].translations;
        sampling.run();
        c.set_pose(poses[i]);
      }
      c.update(dt);
      // What a renderer reads: the interpolation's buffers and share each update, the normals when they change.
      const deform::Character::Interpolation shown = c.interpolation();
      benchmark::DoNotOptimize(shown.to.data());
      benchmark::DoNotOptimize(shown.from.data());
      benchmark::DoNotOptimize(shown.share);
      if (deforms) benchmark::DoNotOptimize(c.normals().data());
    }
  }
};

void level_crowd(benchmark::State& state) {
  LevelCrowd crowd(std::uint32_t(state.range(1)));
  deform::ThreadPool pool(unsigned(state.range(0)));
  crowd.warm_up(pool);
  const std::function<void(std::size_t, std::size_t)> range = [&](std::size_t begin, std::size_t end) {
    crowd.update(begin, end);
  };
  std::vector<double> frame_ms;  // each frame's wall time: the target is per frame, not on average
  frame_ms.reserve(std::size_t(state.max_iterations));
  for (auto _ : state) {
    const auto start = std::chrono::steady_clock::now();
    pool.parallel_for(big_crowd_size, 1, range);
    frame_ms.push_back(std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count());
  }
  state.SetItemsProcessed(state.iterations() * std::int64_t(big_crowd_size));
  std::sort(frame_ms.begin(), frame_ms.end());
  state.counters["frame_p50_ms"] = frame_ms[frame_ms.size() / 2];
  state.counters["frame_p90_ms"] = frame_ms[frame_ms.size() * 9 / 10];
  for (std::size_t l = 1; l < crowd.errors.size(); ++l) {
    state.counters["error_mean_l" + std::to_string(l)] = crowd.errors[l].mean;
    state.counters["error_max_l" + std::to_string(l)] = crowd.errors[l].max;
  }
  for (std::size_t l = 0; l < crowd.influences.size(); ++l) {
    state.counters["points_influences_l" + std::to_string(l)] = double(crowd.influences[l]);
    state.counters["points_l" + std::to_string(l)] = double(crowd.points[l]);
  }
}

BENCHMARK(level_crowd)
    ->Name("crowd/builtin_10000")
    ->ArgNames({"threads", "level1_interval"})
    ->ArgsProduct({{1, 2}, {1, 2}})
    ->UseRealTime()
    ->Unit(benchmark::kMillisecond);

}  // namespace
