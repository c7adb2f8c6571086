// motion_study: the frame-rate and scale study of secondary motion (docs/elasticity.md, "Measured").
//   motion_study                  prints the table
//   motion_study --csv FILE       also writes the whip's tip height over time at 15 and 240 Hz, libdeform and naive,
//                                 for tools/motion_study/plot.py
//   motion_study --check          exits 1 when a libdeform row misses its target
//   motion_study --flesh-csv FILE writes the built-in run's legs' and arms' lengths over time (rigid, tuned jiggle,
//                                 untamed jiggle) for tools/motion_study/plot.py, and prints the flesh measures, the
//                                 imported characters' (assimp-testmodels, default_rig) first; --imported-csv FILE
//                                 also writes Testwuson's run's legs (rigid, tuned, every lattice at inertia 1)
//   motion_study --character      the whole built-in character (every limb's lattice, the ponytail) on its walk and
//                                 run at 30, 60 and 144 Hz against 240 Hz, every 1/3 s (with --check: against 0.5%)
#include <cstdio>
#include <cstring>
#include <fstream>
#include <iostream>
#include <string>

#include "deform/offline/rig.hpp"
#include "deform/runtime/error.hpp"
#include "study.hpp"
#ifdef DEFORM_HAVE_IMPORT
#include <filesystem>

#include "deform/import/import.hpp"
#endif

namespace {

using motion_study::Method;

// The whole character at 30, 60 and 144 Hz against 240 Hz: the largest distance of any surface point, and of any
// of the ponytail's spring points, as a percentage of the 240 Hz run's amplitude (each point's largest range).
int whole_character(bool check) {
  constexpr double seconds = 2.0;
  bool met = true;
  std::printf("| clip | inertia | rate | all points | ponytail |\n|---|---|---:|---:|---:|\n");
  for (const char* clip : {"walk", "run"}) {
    const deform::Rig rig = motion_study::tuned_full_rig();
    for (const float inertia : {-1.0f, 1.0f}) {
      const motion_study::CharacterPaths reference =
          motion_study::play_character(rig, clip, 240.0, seconds, 3.0, inertia);
      const double all = motion_study::amplitude_of(reference.surface);
      const double tail = motion_study::amplitude_of(reference.ponytail);
      for (const double hz : {30.0, 60.0, 144.0}) {
        const motion_study::CharacterPaths run = motion_study::play_character(rig, clip, hz, seconds, 3.0, inertia);
        const double a = 100.0 * motion_study::largest_difference(run.surface, reference.surface) / all;
        const double p = 100.0 * motion_study::largest_difference(run.ponytail, reference.ponytail) / tail;
        std::printf("| %s | %s | %.0f Hz | %.3f%% | %.3f%% |\n", clip, inertia < 0.0f ? "tuned" : "1", hz, a, p);
        met = met && a <= 0.5 && p <= 0.5;
      }
      std::printf("| %s | %s | amplitude | %.3f m | %.3f m |\n", clip, inertia < 0.0f ? "tuned" : "1", all, tail);
    }
  }
  if (check && !met) {
    std::cerr << "motion_study: the whole character misses 0.5%\n";
    return 1;
  }
  return 0;
}

// The imported characters of Debian's assimp-testmodels on their own clips, with default_rig and the viewer's
// default (every lattice its part's tuned inertia: set_inertia_scale(1)), against the rigid clip; and the same with
// every lattice at inertia 1, as the slider set them before it scaled the parts. Nothing where the importer is not
// built or the models are not installed.
// Writes the limbs' lengths over the last of those clips (Testwuson's run) to `csv` when given: rigid, tuned, every
// lattice at 1; a header alone where nothing was measured.
bool imported_flesh(const char* csv) {
  std::vector<std::string> limbs;
  std::vector<double> times;
  std::vector<std::vector<double>> rigid, tuned, every;
#ifdef DEFORM_HAVE_IMPORT
  bool header = false;
  for (const motion_study::ImportedClip& c : motion_study::imported_clips()) {
    if (!std::filesystem::exists(c.file)) continue;
    const deform::ImportedModel imported = deform::import_model(c.file);
    const deform::Rig rig = deform::default_rig(imported.model);
    deform::Rig every_one = rig;  // the old slider at 1: every lattice inertia 1, with its part's bound and share
    for (deform::LatticeSpec& lattice : every_one.lattices) lattice.motion.inertia = 1.0f;
    for (const deform::Animation& clip : imported.clips) {
      if (clip.name != c.clip) continue;
      if (!header) {
        std::printf(
            "| model | clip | lattices | limbs | inertia | largest limb length change | largest lattice volume "
            "change | largest jiggle, model units (%% of height) |\n|---|---|---:|---:|---|---:|---:|---:|\n");
        header = true;
      }
      const double seconds = motion_study::measured_seconds(clip);
      for (const bool scaled : {true, false}) {
        const motion_study::FleshMeasure m = motion_study::measure_flesh(imported.model, clip, scaled ? rig : every_one,
                                                                         60.0, seconds, scaled ? 1.0f : -1.0f);
        std::printf("| %s | %s | %zu | %zu | %s | %.2f%% (%s) | %.2f%% (%s) | %.3g (%.2f%%) |\n",
                    std::filesystem::path(c.file).filename().c_str(), c.clip, rig.lattices.size(), m.limbs.size(),
                    scaled ? "tuned (scale 1)" : "every lattice 1", m.limb_percent, m.worst_limb.c_str(),
                    m.volume_percent, m.worst_lattice.c_str(), m.jiggle, m.jiggle_percent());
        limbs = m.limbs, times = m.times, rigid = m.rigid_length;
        (scaled ? tuned : every) = m.limb_length;
      }
    }
  }
  if (header) std::printf("\n");
#endif
  if (csv == nullptr) return true;
  std::ofstream out(csv);
  out << "t";
  for (const std::string& limb : limbs) out << "," << limb << "_rigid," << limb << "_tuned," << limb << "_every";
  out << "\n";
  for (std::size_t k = 0; k < times.size(); ++k) {
    out << times[k];
    for (std::size_t l = 0; l < limbs.size(); ++l)
      out << "," << rigid[l][k] << "," << tuned[l][k] << "," << every[l][k];
    out << "\n";
  }
  if (!out) std::cerr << "motion_study: could not write " << csv << "\n";
  return bool(out);
}

// The flesh measures of the tuned jiggle on the walk and the run, and the run's limbs over time for the figure: the
// rigid run, the tuned jiggle, and the untamed one (every lattice a free mass, inertia 1, nothing bounded).
int flesh(const char* csv, const char* imported_csv) {
  const deform::Rig tuned = motion_study::tuned_full_rig();
  deform::Rig untamed = tuned;
  for (deform::LatticeSpec& lattice : untamed.lattices)  // the part kept: the limbs are found by it
    lattice.motion = {1.0f, glm::vec3(0.0f), 1.0f, 1.0f, 1.0f, lattice.motion.part};
  deform::Rig every_one = tuned;
  for (deform::LatticeSpec& lattice : every_one.lattices) lattice.motion.inertia = 1.0f;
  if (!imported_flesh(imported_csv)) return 1;
  std::printf("| clip | motion | largest limb length change | largest lattice volume change | largest jiggle |\n");
  std::printf("|---|---|---:|---:|---:|\n");
  motion_study::FleshMeasure run_tuned, run_untamed;
  for (const char* clip : {"walk", "run"}) {
    for (const int kind : {0, 1, 2}) {
      const deform::Rig& rig = kind == 0 ? tuned : kind == 1 ? every_one : untamed;
      const motion_study::FleshMeasure m = motion_study::measure_flesh(rig, clip, 60.0, 2.0);
      const char* names[] = {"tuned (default_lattice_motion; `--inertia 1`, the viewer's 1)",
                             "inertia 1 on every lattice, the parts' bounds (the knob at 1 before it scaled)",
                             "untamed (inertia 1, unbounded)"};
      std::printf("| %s | %s | %.2f%% (%s) | %.2f%% (%s) | %.0f mm |\n", clip, names[kind], m.limb_percent,
                  m.worst_limb.c_str(), m.volume_percent, m.worst_lattice.c_str(), 1000.0 * m.jiggle);
      if (std::string(clip) == "run" && kind != 1) (kind == 0 ? run_tuned : run_untamed) = m;
    }
  }
  std::ofstream out(csv);
  out << "t";
  for (const std::string& limb : run_tuned.limbs)
    out << "," << limb << "_rigid," << limb << "_tuned," << limb << "_untamed";
  out << "\n";
  for (std::size_t k = 0; k < run_tuned.times.size(); ++k) {
    out << run_tuned.times[k];
    for (std::size_t l = 0; l < run_tuned.limbs.size(); ++l)
      out << "," << run_tuned.rigid_length[l][k] << "," << run_tuned.limb_length[l][k] << ","
          << run_untamed.limb_length[l][k];
    out << "\n";
  }
  if (!out) {
    std::cerr << "motion_study: could not write " << csv << "\n";
    return 1;
  }
  return 0;
}

int run(int argc, char** argv) {
  const char* csv = nullptr;
  bool check = false;
  bool character = false;
  const char* flesh_csv = nullptr;
  const char* imported_csv = nullptr;
  for (int i = 1; i < argc; ++i) {
    if (std::strcmp(argv[i], "--csv") == 0 && i + 1 < argc) {
      csv = argv[++i];
    } else if (std::strcmp(argv[i], "--check") == 0) {
      check = true;
    } else if (std::strcmp(argv[i], "--flesh-csv") == 0 && i + 1 < argc) {
      flesh_csv = argv[++i];
    } else if (std::strcmp(argv[i], "--imported-csv") == 0 && i + 1 < argc) {
      imported_csv = argv[++i];
    } else if (std::strcmp(argv[i], "--character") == 0) {
      character = true;
    } else {
      std::cerr << "usage: motion_study [--csv FILE] [--check] [--character]"
                   " [--flesh-csv FILE [--imported-csv FILE]]\n";
      return 2;
    }
  }
  if (character) return whole_character(check);
  if (flesh_csv != nullptr) return flesh(flesh_csv, imported_csv);
  constexpr double whip_seconds = 3.0, walk_seconds = 2.0;
  const auto whip = [](Method method, bool collider) {
    return [=](const std::vector<double>& times, double scale) {
      return motion_study::whip_tip(method, times, scale, collider);
    };
  };
  const auto walk = [](Method method) {
    return
        [=](const std::vector<double>& times, double scale) { return motion_study::walk_hand(method, times, scale); };
  };
  struct Target {
    motion_study::Row row;
    double spread;          // the target for spread_percent (libdeform rows; 0: none)
    double spread_from_30;  // for spread_without_15_percent
  };
  std::vector<Target> rows = {
      {motion_study::measure("whip, 6-link chain", "libdeform", whip_seconds, whip(Method::libdeform, false)), 0.5,
       0.5},
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
