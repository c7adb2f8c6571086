// motion_study: the frame-rate and scale study of secondary motion (docs/elasticity.md, "Measured").
//   motion_study                  prints the table
//   motion_study --csv FILE       also writes the whip's tip height over time at 15 and 240 Hz, libdeform and naive,
//                                 for tools/motion_study/plot.py
//   motion_study --check          exits 1 when a libdeform row misses its target
#include <cstdio>
#include <cstring>
#include <fstream>
#include <iostream>
#include <string>

#include "deform/runtime/error.hpp"
#include "study.hpp"

namespace {

using motion_study::Method;

int run(int argc, char** argv) {
  const char* csv = nullptr;
  bool check = false;
  for (int i = 1; i < argc; ++i) {
    if (std::strcmp(argv[i], "--csv") == 0 && i + 1 < argc) {
      csv = argv[++i];
    } else if (std::strcmp(argv[i], "--check") == 0) {
      check = true;
    } else {
      std::cerr << "usage: motion_study [--csv FILE] [--check]\n";
      return 2;
    }
  }
  constexpr double whip_seconds = 3.0, walk_seconds = 2.0;
  const auto whip = [](Method method, bool collider) {
    return [=](const std::vector<double>& times, double scale) {
      return motion_study::whip_tip(method, times, scale, collider);
    };
  };
  const auto walk = [](Method method) {
    return [=](const std::vector<double>& times, double scale) { return motion_study::walk_hand(method, times, scale); };
  };
  struct Target {
    motion_study::Row row;
    double spread;           // the target for spread_percent (libdeform rows; 0: none)
    double spread_from_30;   // for spread_without_15_percent
  };
  std::vector<Target> rows = {
      {motion_study::measure("whip, 6-link chain", "libdeform", whip_seconds, whip(Method::libdeform, false)), 0.5, 0.5},
      {motion_study::measure("whip, 6-link chain", "naive (VRM)", whip_seconds, whip(Method::naive, false)), 0, 0},
      {motion_study::measure("whip + collider", "libdeform", whip_seconds, whip(Method::libdeform, true)), 2.0, 2.0},
      {motion_study::measure("whip + collider", "naive (VRM)", whip_seconds, whip(Method::naive, true)), 0, 0},
      {motion_study::measure("walk, jiggling hand", "libdeform", walk_seconds, walk(Method::libdeform)), 1.0, 0.5},
      {motion_study::measure("walk, jiggling hand", "naive (Verlet)", walk_seconds, walk(Method::naive)), 0, 0},
  };
  std::printf("| motion | method | spread 15-240 Hz + jittered | without 15 Hz | scale 0.01 / 100 vs scaled |\n");
  std::printf("|---|---|---:|---:|---:|\n");
  bool met = true;
  for (const Target& t : rows) {
    std::printf("| %s | %s | %.3f%% | %.3f%% | %.3f%% |\n", t.row.motion.c_str(), t.row.method.c_str(),
                t.row.spread_percent, t.row.spread_without_15_percent, t.row.scale_percent);
    if (t.spread > 0.0) {
      met = met && t.row.spread_percent <= t.spread && t.row.spread_without_15_percent <= t.spread_from_30 &&
            t.row.scale_percent <= 0.5;
    }
  }
  if (csv != nullptr) {
    std::ofstream out(csv);
    out << "t,libdeform_15,libdeform_240,naive_15,naive_240\n";
    const motion_study::Path paths[] = {
        motion_study::whip_tip(Method::libdeform, motion_study::frame_times(15, whip_seconds, false), 1.0, false),
        motion_study::whip_tip(Method::libdeform, motion_study::frame_times(240, whip_seconds, false), 1.0, false),
        motion_study::whip_tip(Method::naive, motion_study::frame_times(15, whip_seconds, false), 1.0, false),
        motion_study::whip_tip(Method::naive, motion_study::frame_times(240, whip_seconds, false), 1.0, false)};
    for (std::size_t k = 0; k < paths[0].size(); ++k) {
      out << double(k + 1) / motion_study::checkpoint_rate;
      for (const motion_study::Path& path : paths) out << "," << path[k].y;
      out << "\n";
    }
    if (!out) {
      std::cerr << "motion_study: could not write " << csv << "\n";
      return 1;
    }
  }
  if (check && !met) {
    std::cerr << "motion_study: a libdeform row misses its target\n";
    return 1;
  }
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  try {
    return run(argc, argv);
  } catch (const deform::Error& error) {
    std::cerr << "motion_study: " << error.what() << "\n";
    return 2;
  }
}
