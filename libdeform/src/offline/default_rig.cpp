// A rig for any rigged model: its limbs found from the skeleton's structure and skin weights, names as hints
// (rig.hpp states the rules; docs/ik.md, "Default rigs", explains them).
#include <algorithm>
#include <cctype>
#include <cmath>
#include <string>
#include <vector>

#include "deform/offline/rig.hpp"
#include "deform/runtime/error.hpp"
namespace deform {
namespace {

std::string lower(std::string text) {
  std::transform(text.begin(), text.end(), text.begin(), [](unsigned char c) { return char(std::tolower(c)); });
  return text;
}

// What a bone's name says: its side (+1 left, -1 right, 0 none), its role in a limb, and whether it is a helper.
enum class Role : std::uint8_t { none, clavicle, upper_arm, forearm, hand, thigh, shin, foot, head, tail, helper };
enum class Naming : std::uint8_t { none, generic, mixamo, rigify, unreal, vrm };
struct NameHint {
  int side = 0;
  Role role = Role::none;
  Naming naming = Naming::none;
};

bool has_word(const std::string& text, std::string_view word) { return text.find(word) != std::string::npos; }

// Reads a name in the conventions rig.hpp lists. The side marker is taken off before the role is read, so that
// "LeftUpLeg" is an up-leg on the left and "hand.L" a hand on the left.
NameHint read_name(const std::string& original) {
  NameHint hint;
  std::string name = original;
  if (const auto colon = name.find_last_of(":|"); colon != std::string::npos) {  // mixamorig:, Armature|
    if (lower(name.substr(0, colon)).starts_with("mixamorig")) hint.naming = Naming::mixamo;
    name = name.substr(colon + 1);
  }
  std::string low = lower(name);
  if (low.starts_with("def-")) hint.naming = Naming::rigify, low = low.substr(4), name = name.substr(4);
  std::string letters;  // "Hand_IK" and "HandIK" read alike
  for (const char c : low)
    if (std::isalpha(static_cast<unsigned char>(c))) letters += c;
  if (low.starts_with("mch-") || low.starts_with("org-") || low.starts_with("ik_") || low.starts_with("ik-") ||
      letters.starts_with("ik") || letters.ends_with("ik") || has_word(low, "_ik") || has_word(low, ".ik") ||
      has_word(letters, "ikl") || has_word(letters, "ikr") || has_word(letters, "goal") || has_word(letters, "pole") ||
      has_word(letters, "twist") || has_word(letters, "target") || has_word(letters, "ctrl") ||
      has_word(letters, "control") || has_word(letters, "helper") || has_word(letters, "roll")) {
    hint.role = Role::helper;
  }
  // Side markers: VRoid's J_Bip_L_, Mixamo's and VRM's Left/left prefix, Blender's .L/_L/-L suffix, l_ prefixes.
  std::string base = low;
  const auto take = [&](std::size_t at, std::size_t length, int side) {
    base = low.substr(0, at) + low.substr(at + length);
    hint.side = side;
  };
  if (low.starts_with("j_bip_l_") || low.starts_with("j_bip_r_")) {
    hint.naming = Naming::vrm;
    take(0, 8, low[6] == 'l' ? 1 : -1);
  } else if (low.starts_with("left") || low.starts_with("right")) {
    const bool left = low.starts_with("left");
    if (hint.naming == Naming::none) hint.naming = name[0] == 'l' ? Naming::vrm : Naming::mixamo;
    take(0, left ? 4 : 5, left ? 1 : -1);
  } else if (low.size() > 2 && (low.ends_with(".l") || low.ends_with("_l") || low.ends_with("-l") ||
                                low.ends_with(".r") || low.ends_with("_r") || low.ends_with("-r"))) {
    take(low.size() - 2, 2, low.back() == 'l' ? 1 : -1);
    if (hint.naming == Naming::none) hint.naming = low[low.size() - 2] == '_' ? Naming::unreal : Naming::rigify;
  } else if (low.ends_with("_left") || low.ends_with("_right")) {  // "B_Hand_Left"
    take(low.rfind('_'), low.ends_with("_left") ? 5 : 6, low.ends_with("_left") ? 1 : -1);
  } else if (low.starts_with("l_") || low.starts_with("r_") || low.starts_with("l.") || low.starts_with("r.")) {
    take(0, 2, low[0] == 'l' ? 1 : -1);
  } else if (const auto l = low.find("_l_"), r = low.find("_r_"); l != std::string::npos || r != std::string::npos) {
    take(l != std::string::npos ? l : r, 2, l != std::string::npos ? 1 : -1);  // "HindLeg_L_01"
  } else if (const auto ls = low.find(" l "), rs = low.find(" r ");
             ls != std::string::npos || rs != std::string::npos) {  // 3ds Max's "Bip01 L Hand"
    take(ls != std::string::npos ? ls : rs, 2, ls != std::string::npos ? 1 : -1);
  }
  std::string word;  // letters only: "upper_arm" and "UpperArm" read alike
  for (const char c : base)
    if (std::isalpha(static_cast<unsigned char>(c))) word += c;
  if (hint.role == Role::helper) return hint;
  struct Entry {
    const char* word;
    Role role;
  };
  // Exact words first (Mixamo's "Arm" and "Leg", VRM's "UpperArm"), then words contained ("bipthigh").
  static constexpr Entry exact[] = {
      {"hand", Role::hand},          {"wrist", Role::hand},        {"arm", Role::upper_arm},
      {"upperarm", Role::upper_arm}, {"forearm", Role::forearm},   {"lowerarm", Role::forearm},
      {"shoulder", Role::clavicle},  {"clavicle", Role::clavicle}, {"collar", Role::clavicle},
      {"upleg", Role::thigh},        {"upperleg", Role::thigh},    {"thigh", Role::thigh},
      {"leg", Role::shin},           {"lowerleg", Role::shin},     {"shin", Role::shin},
      {"calf", Role::shin},          {"foot", Role::foot},         {"ankle", Role::foot},
      {"head", Role::head},          {"neck", Role::head},         {"tail", Role::tail}};
  for (const Entry& e : exact)
    if (word == e.word) hint.role = e.role;
  if (hint.role == Role::none) {
    static constexpr Entry contained[] = {
        {"forearm", Role::forearm},    {"lowerarm", Role::forearm}, {"upperarm", Role::upper_arm},
        {"clavicle", Role::clavicle},  {"thigh", Role::thigh},      {"calf", Role::shin},
        {"shin", Role::shin},          {"hand", Role::hand},        {"wrist", Role::hand},
        {"foot", Role::foot},          {"ankle", Role::foot},       {"hindleg", Role::thigh},
        {"backleg", Role::thigh},      {"rearleg", Role::thigh},    {"foreleg", Role::upper_arm},
        {"frontleg", Role::upper_arm}, {"tail", Role::tail},        {"neck", Role::head},
        {"head", Role::head}};
    for (const Entry& e : contained)
      if (has_word(word, e.word)) {
        hint.role = e.role;
        break;
      }
  }
  if (hint.role != Role::none && hint.naming == Naming::none) hint.naming = Naming::generic;
  return hint;
}

const char* naming_name(Naming naming) {
  switch (naming) {
    case Naming::generic: return "generic";
    case Naming::mixamo: return "Mixamo";
    case Naming::rigify: return "Blender";  // .L/.R suffixes: rigify (DEF-), the metarig, hand-made rigs
    case Naming::unreal: return "Unreal mannequin";
    case Naming::vrm: return "VRM";
    case Naming::none: break;
  }
  return "none";
}

// The skeleton as survey_rig() sees it: skin weight per bone and below it, the children that count.
struct Body {
  explicit Body(const Skeleton& s) : skeleton(s) {}
  const Skeleton& skeleton;
  std::int32_t bones = 0;
  std::vector<double> own, subtree;
  std::vector<NameHint> hints;
  std::vector<bool> relevant;                       // carries skin weight itself or below, and is no helper
  std::vector<std::vector<std::int32_t>> children;  // relevant children only
  std::vector<glm::vec3> head;
  std::vector<float> reach;         // how far b's relevant bones (b included) reach from b's parent's head
  std::vector<std::size_t> counts;  // relevant bones in b's subtree, b included
  bool surveyed = true;             // false: too deep to survey (far beyond any character)

  glm::vec3 at(std::int32_t b) const { return head[std::size_t(b)]; }
  // How far the relevant bones from b down reach from b's parent's head (every use measures from there).
  float extent(std::int32_t b) const { return reach[std::size_t(b)]; }
  std::size_t count(std::int32_t b) const { return counts[std::size_t(b)]; }
  // From b down the child that reaches farthest: a limb's bones, with its hand's middle finger or its toes.
  std::vector<std::int32_t> main_path(std::int32_t b) const {
    std::vector<std::int32_t> path{b};
    while (!children[std::size_t(b)].empty()) {
      std::int32_t best = -1;
      float far = -1.0f;
      for (const std::int32_t c : children[std::size_t(b)])
        if (const float e = extent(c); e > far) far = e, best = c;
      path.push_back(b = best);
    }
    return path;
  }
};

Body make_body(const Model& model, RigSurvey& survey) {
  const Skeleton& skeleton = model.skeleton;
  Body body(skeleton);
  body.bones = static_cast<std::int32_t>(skeleton.bone_count());
  const auto n = std::size_t(body.bones);
  body.own.assign(n, 0.0);
  for (std::size_t p = 0; p < model.weights.size(); ++p)
    for (int i = 0; i < max_influences; ++i)
      if (model.weights.bones[p][i] < n) body.own[model.weights.bones[p][i]] += model.weights.weights[p][i];
  for (std::size_t e = 0; e < model.weights.extra_bones.size(); ++e)
    if (model.weights.extra_bones[e] < n) body.own[model.weights.extra_bones[e]] += model.weights.extra_weights[e];
  body.subtree = body.own;
  // Weight below a bone that is not a helper's: a twist bone's own weight does not make its parent a branch.
  std::vector<double> real(n, 0.0);
  body.hints.resize(n);
  for (std::size_t b = 0; b < n; ++b) body.hints[b] = read_name(skeleton.bone(std::int32_t(b)).name);
  for (std::size_t b = 0; b < n; ++b) real[b] = body.hints[b].role == Role::helper ? 0.0 : body.own[b];
  const auto order = skeleton.order();
  for (auto it = order.rbegin(); it != order.rend(); ++it)
    if (const std::int32_t parent = skeleton.bone(*it).parent; parent >= 0) {
      body.subtree[std::size_t(parent)] += body.subtree[std::size_t(*it)];
      real[std::size_t(parent)] += real[std::size_t(*it)];
    }
  body.relevant.assign(n, false);
  body.children.resize(n);
  body.head.resize(n);
  for (std::size_t b = 0; b < n; ++b) {
    body.head[b] = glm::vec3(skeleton.bind_world()[b][3]);
    if (!(body.subtree[b] > 0.0)) {
      survey.skipped.emplace_back(std::int32_t(b), "no vertex is skinned to it or to a bone below it");
    } else if (!(real[b] > 0.0)) {
      survey.skipped.emplace_back(std::int32_t(b),
                                  "a helper's name (twist, IK, pole, target, control) and no "
                                  "other skinned bone below it");
    } else {
      body.relevant[b] = true;
    }
  }
  // A bone named as a hand or foot under a named forearm or shin that counts counts too, skin weight or not: some
  // rigs skin the hand to an IK goal elsewhere (mrfixit's HandGoal.L), and the named hand is still where the arm ends.
  for (const std::int32_t b : order) {
    const std::int32_t parent = skeleton.bone(b).parent;
    const Role role = body.hints[std::size_t(b)].role;
    const Role above = parent >= 0 ? body.hints[std::size_t(parent)].role : Role::none;
    if (parent >= 0 && !body.relevant[std::size_t(b)] && body.relevant[std::size_t(parent)] &&
        (role == Role::hand || role == Role::foot) && (above == Role::forearm || above == Role::shin)) {
      body.relevant[std::size_t(b)] = true;
      std::erase_if(survey.skipped, [&](const auto& entry) { return entry.first == b; });
    }
    if (parent >= 0 && body.relevant[std::size_t(b)]) body.children[std::size_t(parent)].push_back(b);
  }
  // Subtree counts, children before parents; the reach of each bone's subtree from its parent, every relevant bone
  // walking up its ancestors: the pairs of ancestor and descendant, a few thousand on a character. A skeleton with
  // more than 2^24 of them (a chain of thousands of bones) is not surveyed.
  body.counts.assign(n, 1);
  for (auto it = order.rbegin(); it != order.rend(); ++it)
    if (const std::int32_t parent = skeleton.bone(*it).parent; parent >= 0 && body.relevant[std::size_t(*it)])
      body.counts[std::size_t(parent)] += body.counts[std::size_t(*it)];
  body.reach.assign(n, 0.0f);
  std::size_t steps = 0;
  for (std::size_t d = 0; d < n && body.surveyed; ++d) {
    if (!body.relevant[d]) continue;
    for (std::int32_t a = std::int32_t(d); skeleton.bone(a).parent >= 0; a = skeleton.bone(a).parent) {
      const std::int32_t parent = skeleton.bone(a).parent;
      float& far = body.reach[std::size_t(a)];
      far = std::max(far, glm::length(body.head[d] - body.head[std::size_t(parent)]));
      if (++steps > (std::size_t(1) << 24)) body.surveyed = false;
    }
  }
  return body;
}

// A limb before its kind is known: the branch it starts with and its bones down to the farthest tip.
struct Branch {
  std::int32_t from = -1;  // the bone it branches from (chest, pelvis)
  std::vector<std::int32_t> path;
  int side = 0;
  float extent = 0.0f;
};

// Splits a limb's path into (reach root, upper, lower, end) indices; `arm`: a bone before the upper limb is a
// clavicle and the reach starts there. The end is the named hand or foot when the path has one, else the bone after
// the two longest consecutive bones (upper and lower arm or leg, longer than a hand or a finger).
struct Segments {
  std::size_t root = 0, upper = 0, lower = 0, end = 0;
  bool named = false;
};
Segments segment(const Body& body, const std::vector<std::int32_t>& path, bool arm) {
  Segments s;
  const std::size_t n = path.size();
  for (std::size_t i = 0; i < n; ++i) {
    const Role role = body.hints[std::size_t(path[i])].role;
    if (role == Role::hand || role == Role::foot) {
      s.end = i, s.named = true;
      break;
    }
  }
  if (!s.named) {
    if (n >= 3) {
      float best = -1.0f;
      for (std::size_t i = 0; i + 2 < n; ++i) {
        const float length = glm::length(body.at(path[i + 1]) - body.at(path[i])) +
                             glm::length(body.at(path[i + 2]) - body.at(path[i + 1]));
        if (length > best * 1.05f) best = length, s.end = i + 2;  // a tie goes to the bones nearer the body
      }
    } else {
      s.end = n - 1;
    }
  }
  s.lower = s.end > 0 ? s.end - 1 : 0;
  s.upper = s.end > 1 ? s.end - 2 : s.lower;
  s.root = arm && s.upper > 0 ? s.upper - 1 : s.upper;
  return s;
}

Limb make_limb(const Body& body, const Branch& branch, LimbKind kind, const std::string& why) {
  Limb limb;
  limb.kind = kind;
  limb.side = branch.side;
  const Segments s = segment(body, branch.path, kind == LimbKind::arm);
  for (std::size_t i = s.root; i <= s.end; ++i) limb.chain.push_back(branch.path[i]);
  for (std::size_t i = s.upper; i <= s.end; ++i)
    if (body.own[std::size_t(branch.path[i])] > 0.0 &&
        std::find(limb.lattices.begin(), limb.lattices.end(), branch.path[i]) == limb.lattices.end())
      limb.lattices.push_back(branch.path[i]);
  const Skeleton& sk = body.skeleton;
  limb.why = why + "; " +
             (s.named ? "'" + sk.bone(branch.path[s.end]).name + "' by its name"
                      : "the end after the two longest bones ('" + sk.bone(branch.path[s.upper]).name + "', '" +
                            sk.bone(branch.path[s.lower]).name + "')");
  limb.why += kind == LimbKind::arm && s.root < s.upper          ? "; the reach starts at the clavicle"
              : kind == LimbKind::arm                            ? "; no clavicle: the reach starts at the shoulder"
              : kind == LimbKind::neck || kind == LimbKind::tail ? ""
                                                                 : "; the reach starts at the hip joint";
  return limb;
}

int side_of(const Body& body, const std::vector<std::int32_t>& path) {
  for (const std::int32_t b : path)
    if (body.hints[std::size_t(b)].side != 0) return body.hints[std::size_t(b)].side;
  return 0;
}

int depth(const Skeleton& sk, std::int32_t b) {
  int d = 0;
  while ((b = sk.bone(b).parent) >= 0) ++d;
  return d;
}

// Two branches from one bone that mirror each other; `extent` the larger one's.
struct Pair {
  Branch a, b;
  float extent = 0.0f;
};

bool has_role(const Body& body, const Pair& p, Role role) {
  for (const Branch* branch : {&p.a, &p.b})
    for (const std::int32_t b : branch->path)
      if (body.hints[std::size_t(b)].role == role) return true;
  return false;
}

// Mirrored pairs among `bone`'s children: two with the same bone count (within a quarter) and extent (within 20%)
// whose tips lie apart and whose paths mirror each other, taken most alike first; appended to `pairs`.
void pair_children(const Body& body, std::int32_t bone, std::vector<Pair>& pairs) {
  const auto& kids = body.children[std::size_t(bone)];
  if (kids.size() > 32) return;  // a body branches into a few limbs, a hand into a few fingers
  std::vector<bool> used(kids.size(), false);
  struct Candidate {
    float mismatch;
    std::size_t i, j;
  };
  std::vector<Candidate> candidates;
  for (std::size_t i = 0; i < kids.size(); ++i)
    for (std::size_t j = i + 1; j < kids.size(); ++j) {
      const float ei = body.extent(kids[i]), ej = body.extent(kids[j]);
      const std::size_t ci = body.count(kids[i]), cj = body.count(kids[j]);
      if (!(std::min(ei, ej) > 0.8f * std::max(ei, ej)) || 4 * std::min(ci, cj) < 3 * std::max(ci, cj)) continue;
      const auto pi = body.main_path(kids[i]), pj = body.main_path(kids[j]);
      const glm::vec3 apart = body.at(pi.back()) - body.at(pj.back());
      if (pi.size() != pj.size() || !(glm::length(apart) > 0.05f * std::max(ei, ej))) continue;
      // Mirror images: the plane halfway between the tips, through `bone`, maps one path onto the other.
      const glm::vec3 normal = glm::normalize(apart), middle = 0.5f * (body.at(pi.back()) + body.at(pj.back()));
      const auto mirror = [&](glm::vec3 p) { return p - 2.0f * glm::dot(p - middle, normal) * normal; };
      bool mirrored = std::abs(glm::dot(body.at(bone) - middle, normal)) < 0.15f * std::max(ei, ej);
      for (std::size_t k = 0; k < pi.size() && mirrored; ++k)
        mirrored = glm::length(mirror(body.at(pi[k])) - body.at(pj[k])) < 0.15f * std::max(ei, ej);
      if (!mirrored) continue;
      candidates.push_back({std::abs(ei - ej) / std::max(ei, ej) + float(ci > cj ? ci - cj : cj - ci), i, j});
    }
  std::sort(candidates.begin(), candidates.end(),
            [](const Candidate& x, const Candidate& y) { return x.mismatch < y.mismatch; });
  for (const Candidate& c : candidates) {
    if (used[c.i] || used[c.j]) continue;
    used[c.i] = used[c.j] = true;
    Pair pair;
    pair.a = {bone, body.main_path(kids[c.i]), 0, body.extent(kids[c.i])};
    pair.b = {bone, body.main_path(kids[c.j]), 0, body.extent(kids[c.j])};
    pair.extent = std::max(pair.a.extent, pair.b.extent);
    pairs.push_back(std::move(pair));
  }
}

// A pair whose branch runs through a helper's name (mrfixit's ArmIK.L and HandGoal.L, which carry the hand's skin
// but hang from the spine) is an IK set-up, not a limb: dropped, and said so in `survey.skipped`.
void drop_ik_setups(const Body& body, std::vector<Pair>& pairs, RigSurvey& survey) {
  std::erase_if(pairs, [&](const Pair& p) {
    const auto helper = [&](const Branch& branch) {
      for (const std::int32_t b : branch.path)
        if (body.hints[std::size_t(b)].role == Role::helper) return b;
      return std::int32_t(-1);
    };
    if (helper(p.a) < 0 && helper(p.b) < 0) return false;
    for (const Branch* side : {&p.a, &p.b})
      if (const std::int32_t b = helper(*side); b >= 0)
        survey.skipped.emplace_back(side->path.front(), "not a limb: an IK set-up (its branch runs through '" +
                                                            body.skeleton.bone(b).name + "', a helper's name)");
    return true;
  });
}

// The pairs that are limbs: the large ones, not inside another pair (fingers, toes) and at least half the largest
// one's extent; at most eight, the largest (a spider's legs fit; more is no body). Each with its sides set (names,
// else +X is the character's left), left first.
std::vector<Pair> limb_pairs(const Body& body, const std::vector<Pair>& pairs) {
  const Skeleton& sk = body.skeleton;
  float largest = 0.0f;
  for (const Pair& p : pairs) largest = std::max(largest, p.extent);
  std::vector<Pair> limbs;
  for (const Pair& p : pairs) {
    if (p.extent < 0.5f * largest) continue;
    bool inside = false;
    for (const Pair& q : pairs)
      if (&q != &p && (sk.is_ancestor(q.a.path.front(), p.a.from) || sk.is_ancestor(q.b.path.front(), p.a.from))) {
        inside = true;
        break;
      }
    if (!inside) limbs.push_back(p);
  }
  std::stable_sort(limbs.begin(), limbs.end(), [](const Pair& x, const Pair& y) { return x.extent > y.extent; });
  if (limbs.size() > 8) limbs.resize(8);
  for (Pair& p : limbs) {
    p.a.side = side_of(body, p.a.path);
    p.b.side = side_of(body, p.b.path);
    if (p.a.side == 0 || p.a.side == p.b.side) {
      const bool a_left = body.at(p.a.path.back()).x >= body.at(p.b.path.back()).x;
      p.a.side = a_left ? 1 : -1;
      p.b.side = -p.a.side;
    }
    if (p.a.side < 0) std::swap(p.a, p.b);  // left first
  }
  return limbs;
}

// Which of the limb pairs are the legs and which the arms (null: none). Legs: the named pair (feet, thighs), else
// the pair nearer the root (then the lower one). Arms: the named one (hands), else the other of two. Sorts `limbs`,
// legs first; the pointers are into it.
std::pair<const Pair*, const Pair*> legs_and_arms(const Body& body, std::vector<Pair>& limbs) {
  const auto leglike = [&](const Pair& p) {
    return has_role(body, p, Role::foot) || has_role(body, p, Role::thigh) || has_role(body, p, Role::shin);
  };
  std::sort(limbs.begin(), limbs.end(), [&](const Pair& x, const Pair& y) {
    const bool xl = leglike(x), yl = leglike(y);
    if (xl != yl) return xl;
    return depth(body.skeleton, x.a.from) < depth(body.skeleton, y.a.from);
  });
  const Pair* legs = limbs.empty() ? nullptr : &limbs.front();
  const auto armlike = [&](const Pair& p) {
    return has_role(body, p, Role::hand) || has_role(body, p, Role::upper_arm) || has_role(body, p, Role::forearm) ||
           has_role(body, p, Role::clavicle);
  };
  const Pair* arms = nullptr;
  for (const Pair& p : limbs)
    if (&p != legs && (arms == nullptr || armlike(p))) arms = &p;
  if (legs != nullptr && arms == nullptr && armlike(*legs) && !has_role(body, *legs, Role::foot) &&
      !has_role(body, *legs, Role::thigh))
    std::swap(legs, arms);  // one pair, and it is the arms
  return {legs, arms};
}

// The body's frame from its limbs: the pelvis and up from the legs (from the hip joint to the foot; a model axis
// when within 30 degrees of one), the chest from the arms, and four legs when the hands hang below 30% of the hips'
// height.
void orient_body(const Body& body, const Pair* legs, const Pair* arms, RigSurvey& survey) {
  if (legs != nullptr) {
    survey.pelvis = legs->a.from;
    glm::vec3 down(0.0f);
    for (const Branch* b : {&legs->a, &legs->b}) {
      const Segments s = segment(body, b->path, false);
      down += body.at(b->path[s.end]) - body.at(b->path[s.upper]);
    }
    if (glm::length(down) > 0.0f) survey.up = -glm::normalize(down);
    for (int axis = 0; axis < 3; ++axis)
      if (std::abs(survey.up[axis]) > 0.866f) {
        const float sign = survey.up[axis] > 0.0f ? 1.0f : -1.0f;
        survey.up = glm::vec3(0.0f);
        survey.up[axis] = sign;
      }
  }
  if (arms != nullptr) survey.chest = arms->a.from;
  if (legs != nullptr && arms != nullptr) {
    const auto height = [&](std::int32_t b) { return glm::dot(body.at(b), survey.up); };
    const auto end = [&](const Branch& b) { return b.path[segment(body, b.path, false).end]; };
    const float floor = std::min(height(end(legs->a)), height(end(legs->b)));
    const float hips = height(legs->a.path.front()) - floor;
    const float hands = std::max(height(end(arms->a)), height(end(arms->b))) - floor;
    survey.four_legged = hips > 0.0f && hands < 0.3f * hips;
  }
}

// The naming convention at least three bones follow (the first of mixamo, vrm, unreal, rigify, generic), or none.
Naming body_naming(const Body& body) {
  std::vector<Naming> namings;
  for (const NameHint& hint : body.hints)
    if (hint.naming != Naming::none) namings.push_back(hint.naming);
  Naming naming = Naming::none;
  for (const Naming candidate : {Naming::mixamo, Naming::vrm, Naming::unreal, Naming::rigify, Naming::generic})
    if (std::count(namings.begin(), namings.end(), candidate) >= 3 && naming == Naming::none) naming = candidate;
  return naming;
}

// The limbs of the pairs: arms (or front legs), legs (or hind legs), then any other large pair (a spider's legs) as
// legs too.
void add_paired_limbs(const Body& body, const std::vector<Pair>& limbs, const Pair* legs, const Pair* arms,
                      RigSurvey& survey) {
  const auto why_pair = [&](const Pair& p, const char* what) {
    return std::string(what) + " (a mirrored pair branching from '" + body.skeleton.bone(p.a.from).name + "')";
  };
  if (arms != nullptr) {
    const LimbKind kind = survey.four_legged ? LimbKind::front_leg : LimbKind::arm;
    for (const Branch* b : {&arms->a, &arms->b})
      survey.limbs.push_back(make_limb(body, *b, kind, why_pair(*arms, survey.four_legged ? "front legs" : "arms")));
  }
  if (legs != nullptr) {
    const LimbKind kind = survey.four_legged ? LimbKind::hind_leg : LimbKind::leg;
    for (const Branch* b : {&legs->a, &legs->b})
      survey.limbs.push_back(make_limb(body, *b, kind, why_pair(*legs, survey.four_legged ? "hind legs" : "legs")));
  }
  for (const Pair& p : limbs)
    if (&p != legs && &p != arms)
      for (const Branch* b : {&p.a, &p.b})
        survey.limbs.push_back(make_limb(body, *b, LimbKind::leg, why_pair(p, "legs")));
}

// A named hand or foot no limb holds (an asymmetric rig): its limb runs up to the nearest branch (four at most).
void add_unpaired_limbs(const Body& body, RigSurvey& survey) {
  const Skeleton& sk = body.skeleton;
  for (std::int32_t bone = 0, added = 0; bone < body.bones && added < 4; ++bone) {
    const NameHint& hint = body.hints[std::size_t(bone)];
    if (!body.relevant[std::size_t(bone)] || (hint.role != Role::hand && hint.role != Role::foot)) continue;
    bool held = false;
    for (const Limb& limb : survey.limbs)
      for (const std::int32_t b : limb.chain) held = held || sk.is_ancestor(b, bone) || sk.is_ancestor(bone, b);
    if (held) continue;
    Branch branch;
    std::int32_t top = bone;
    while (sk.bone(top).parent >= 0 && body.children[std::size_t(sk.bone(top).parent)].size() == 1 &&
           body.hints[std::size_t(sk.bone(top).parent)].role != Role::none &&
           body.hints[std::size_t(sk.bone(top).parent)].role != Role::head)
      top = sk.bone(top).parent;
    branch.from = sk.bone(top).parent;
    for (std::int32_t b = bone; b != sk.bone(top).parent; b = sk.bone(b).parent)
      branch.path.insert(branch.path.begin(), b);
    branch.side = hint.side;
    if (branch.from < 0 || branch.path.size() < 2) continue;
    const bool arm = hint.role == Role::hand;
    ++added;
    survey.limbs.push_back(
        make_limb(body, branch, arm ? LimbKind::arm : LimbKind::leg,
                  std::string(arm ? "an arm" : "a leg") + " ending at a bone named '" + sk.bone(bone).name + "'"));
  }
}

// Of `from`'s children other than `skip`'s branches and those leading to `avoid` (-1: none), at least a sixth of
// the legs' extent: the one that names `role` on its way down, else the one reaching farthest. -1 for none.
std::int32_t other_branch(const Body& body, std::int32_t from, const Pair& skip, std::int32_t avoid, Role role,
                          const Pair& legs) {
  std::int32_t best = -1;
  float far = 0.0f;
  bool named = false;
  for (const std::int32_t c : body.children[std::size_t(from)]) {
    if (c == skip.a.path.front() || c == skip.b.path.front() || (avoid >= 0 && body.skeleton.is_ancestor(c, avoid)))
      continue;
    bool names = false;
    for (const std::int32_t b : body.main_path(c)) names = names || body.hints[std::size_t(b)].role == role;
    const float e = body.extent(c);
    if (e >= legs.a.extent / 6.0f && ((names && !named) || (names == named && e > far)))
      far = e, best = c, named = names;
  }
  return best;
}

// A four-legged creature's neck (the chest's branch that is not a front leg) and tail (the pelvis' branch that leads
// neither to a leg nor to the chest), each at least two bones and a sixth of a leg's extent.
void add_neck_and_tail(const Body& body, const Pair& legs, const Pair& arms, RigSurvey& survey) {
  const Skeleton& sk = body.skeleton;
  if (const std::int32_t neck = other_branch(body, arms.a.from, arms, -1, Role::head, legs); neck >= 0) {
    Branch branch{arms.a.from, body.main_path(neck), 0, 0.0f};
    // The head: by name, else the path's last bone with skin weight of its own (past it only tips: ears, nose).
    std::size_t end = branch.path.size() - 1;
    for (std::size_t i = 0; i < branch.path.size(); ++i)
      if (body.hints[std::size_t(branch.path[i])].role == Role::head) end = i;
    branch.path.resize(end + 1);
    if (branch.path.size() >= 2) {
      Limb limb;
      limb.kind = LimbKind::neck;
      limb.chain = branch.path;
      for (std::size_t i = branch.path.size() >= 3 ? branch.path.size() - 3 : 0; i < branch.path.size(); ++i)
        if (body.own[std::size_t(branch.path[i])] > 0.0) limb.lattices.push_back(branch.path[i]);
      limb.why = "the neck and head: the branch from '" + sk.bone(arms.a.from).name +
                 "' that is not a front leg; the reach starts at its first bone";
      survey.limbs.push_back(std::move(limb));
    }
  }
  const std::int32_t pelvis = legs.a.from;
  if (const std::int32_t tail = other_branch(body, pelvis, legs, arms.a.from, Role::tail, legs); tail >= 0) {
    Limb limb;
    limb.kind = LimbKind::tail;
    limb.chain = body.main_path(tail);
    limb.why = "the tail: the branch from '" + sk.bone(pelvis).name +
               "' that leads neither to a leg nor to the chest; a spring chain";
    if (limb.chain.size() >= 2) survey.limbs.push_back(std::move(limb));
  }
}

}  // namespace

const char* limb_kind_name(LimbKind kind) noexcept {
  switch (kind) {
    case LimbKind::arm: return "arm";
    case LimbKind::leg: return "leg";
    case LimbKind::front_leg: return "front_leg";
    case LimbKind::hind_leg: return "hind_leg";
    case LimbKind::neck: return "neck";
    case LimbKind::tail: return "tail";
    case LimbKind::limb: break;
  }
  return "limb";
}

RigSurvey survey_rig(const Model& model) {
  RigSurvey survey;
  const Body body = make_body(model, survey);
  if (!body.surveyed) return survey;
  std::vector<Pair> pairs;
  for (std::int32_t bone = 0; bone < body.bones; ++bone) pair_children(body, bone, pairs);
  drop_ik_setups(body, pairs, survey);
  std::vector<Pair> limbs = limb_pairs(body, pairs);
  const auto [legs, arms] = legs_and_arms(body, limbs);
  orient_body(body, legs, arms, survey);
  survey.naming = naming_name(body_naming(body));
  add_paired_limbs(body, limbs, legs, arms, survey);
  add_unpaired_limbs(body, survey);
  if (survey.four_legged) add_neck_and_tail(body, *legs, *arms, survey);
  return survey;
}

Rig default_rig(const Model& model, std::int32_t effector) {
  const Skeleton& skeleton = model.skeleton;
  const auto bones = static_cast<std::int32_t>(skeleton.bone_count());
  if (effector >= bones) throw Error::in_file(model.name, "bone " + std::to_string(effector), "no such bone");
  const RigSurvey survey = survey_rig(model);
  std::vector<bool> weighted(std::size_t(bones), false);  // skin weight of its own
  for (std::size_t p = 0; p < model.weights.size(); ++p)
    for (int i = 0; i < max_influences; ++i)
      if (model.weights.bones[p][i] < std::uint32_t(bones) && model.weights.weights[p][i] > 0.0f)
        weighted[model.weights.bones[p][i]] = true;

  Rig rig;
  const auto add_lattice = [&](std::int32_t bone, BodyPart part) {
    for (const LatticeSpec& spec : rig.lattices)
      if (spec.bone == bone) return;
    LatticeSpec spec;
    spec.name = skeleton.key(bone);
    spec.bone = bone;
    spec.elastic.oscillator = {150.0f, 0.2f, 1.0f};  // the built-in rig's rubber: about 2 Hz, under-damped
    // Flesh when it moves, as the built-in rigs: the part's bound and far-face share, at no inertia until asked.
    spec.motion = default_lattice_motion(part);
    spec.motion.inertia = 0.0f;
    rig.lattices.push_back(std::move(spec));
  };
  // A limb's chain runs (clavicle,) upper, lower, end: the end is a hand or foot (a neck's, its head). The part is
  // the bone's place in the chain, not in the lattices: an arm whose hand has no lattice of its own (mrfixit's)
  // still has an upper arm and a forearm (rig files store the part: LatticeMotion::part).
  const auto part_of = [](const Limb& limb, std::size_t i) {
    const bool end = limb.lattices[i] == limb.chain.back();
    if (limb.kind == LimbKind::neck) return end ? BodyPart::head : BodyPart::torso;
    if (end) return limb.kind == LimbKind::arm ? BodyPart::hand : BodyPart::foot;
    const auto at = std::find(limb.chain.begin(), limb.chain.end(), limb.lattices[i]);
    return at != limb.chain.end() && at + 2 == limb.chain.end() ? BodyPart::lower_limb : BodyPart::upper_limb;
  };
  for (const Limb& limb : survey.limbs) {
    if (limb.kind == LimbKind::tail) {
      SpringChainSpec tail;
      tail.name = "tail";
      tail.bones = limb.chain;
      tail.frequency = 2.0f;  // no gravity: the tail keeps the shape it was modelled in and swings with the motion
      tail.damping_ratio = 0.4f;
      rig.spring_chains.push_back(std::move(tail));
      continue;
    }
    for (std::size_t i = 0; i < limb.lattices.size(); ++i) add_lattice(limb.lattices[i], part_of(limb, i));
    const std::int32_t end = limb.chain.back(), root = limb.chain.front();
    if (rig.reach_effector < 0 && root != end) {
      rig.reach_effector = end;
      rig.reach_root = root;
    } else if (root != end) {
      rig.reach_chains.push_back({end, root});
    }
  }

  if (effector >= 0) {
    // A chosen effector: its limb's chain when it ends one, else a limb of its own up from it.
    const auto chosen = std::find_if(survey.limbs.begin(), survey.limbs.end(), [&](const Limb& limb) {
      return limb.kind != LimbKind::tail && limb.chain.back() == effector && limb.chain.size() > 1;
    });
    if (chosen == survey.limbs.end()) {
      std::vector<std::int32_t> own;
      std::int32_t top = -1;
      for (std::int32_t b = effector; b >= 0 && own.size() < 3; b = skeleton.bone(b).parent) {
        if (!weighted[std::size_t(b)]) continue;
        own.insert(own.begin(), b);
        top = b;
      }
      for (std::size_t i = 0; i < own.size(); ++i)  // upper, lower, then the chosen end (a hand, say)
        add_lattice(own[i], i + 1 == own.size()   ? BodyPart::hand
                            : i + 2 == own.size() ? BodyPart::lower_limb
                                                  : BodyPart::upper_limb);
      const std::int32_t root = top >= 0 && skeleton.bone(top).parent >= 0 ? skeleton.bone(top).parent : top;
      if (rig.reach_effector >= 0 && rig.reach_effector != effector)
        rig.reach_chains.push_back({rig.reach_effector, rig.reach_root});
      rig.reach_effector = effector;
      rig.reach_root = root == effector ? -1 : root;
    } else {
      if (rig.reach_effector != effector) rig.reach_chains.push_back({rig.reach_effector, rig.reach_root});
      rig.reach_effector = effector;
      rig.reach_root = chosen->chain.front();
    }
    std::erase_if(rig.reach_chains, [&](const Rig::ReachChain& c) { return c.effector == effector; });
    return rig;
  }
  if (rig.reach_effector >= 0) return rig;

  // No limb: the deepest bone with skin weight of its own and up to two weighted ancestors, as for a chosen one.
  std::int32_t deepest = -1;
  std::vector<int> depth(std::size_t(bones), 0);
  for (const std::int32_t b : skeleton.order()) {  // parents first
    if (const std::int32_t parent = skeleton.bone(b).parent; parent >= 0)
      depth[std::size_t(b)] = depth[std::size_t(parent)] + 1;
    if (weighted[std::size_t(b)] && (deepest < 0 || depth[std::size_t(b)] > depth[std::size_t(deepest)] ||
                                     (depth[std::size_t(b)] == depth[std::size_t(deepest)] && b < deepest)))
      deepest = b;
  }
  if (deepest < 0) throw Error::in_file(model.name, "", "no bone carries skin weight, so no lattice can be bound");
  Rig fallback = default_rig(model, deepest);
  fallback.spring_chains = rig.spring_chains;
  return fallback;
}

}  // namespace deform
