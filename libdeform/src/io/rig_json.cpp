// Rig files (JSON): read, validate with context, write. Format: docs/formats.md, "Rig files".
#include <algorithm>
#include <limits>
#include <optional>
#include <nlohmann/json.hpp>
#include <string>

#include "deform/io/atomic_file.hpp"
#include "deform/runtime/error.hpp"
#include "deform/offline/rig.hpp"
#include "deform/io/rig_json.hpp"
#include "deform/io/text.hpp"
#include "json_reader.hpp"
namespace deform {
namespace {

using nlohmann::json;
using ojson = nlohmann::ordered_json;  // written keys keep the documented order

constexpr int rig_format_version = 1;

using detail::JsonReader;

// A bone named by a string value (Skeleton::key: the name, or "#ID").
std::int32_t read_bone(const JsonReader& r, const Skeleton& skeleton) {
  const std::string name = r.text();
  const std::int32_t id = skeleton.find(name);
  if (id < 0) r.fail("unknown bone '" + name + "'");
  return id;
}

// The lattice whose bone is the nearest proper ancestor of lattice i's bone (as DeformerHierarchy defines it).
std::int32_t implied_parent(const std::vector<LatticeSpec>& lattices, const Skeleton& skeleton, std::size_t i) {
  for (std::int32_t b = skeleton.bone(lattices[i].bone).parent; b >= 0; b = skeleton.bone(b).parent) {
    for (std::size_t other = 0; other < lattices.size(); ++other) {
      if (lattices[other].bone == b) return std::int32_t(other);
    }
  }
  return -1;
}

ElasticSettings read_elastic(const JsonReader& r) {
  r.expect_object({"stiffness", "damping_ratio", "mass", "integrator", "verlet_kd", "springs"});
  ElasticSettings e;
  const float big = std::numeric_limits<float>::max();
  if (r.has("stiffness")) e.oscillator.stiffness = r.at("stiffness").number(0.0f, big, true);
  if (r.has("damping_ratio")) e.oscillator.damping_ratio = r.at("damping_ratio").number(0.0f, big);
  if (r.has("mass")) e.oscillator.mass = r.at("mass").number(0.0f, big, true);
  if (r.has("integrator")) {
    const std::string name = r.at("integrator").text();
    if (name == "exact") e.integrator = Integrator::exact;
    else if (name == "verlet") e.integrator = Integrator::verlet;
    else r.at("integrator").fail("must be \"exact\" or \"verlet\"");
  }
  if (r.has("verlet_kd")) e.verlet_kd = r.at("verlet_kd").number(0.0f, 1.0f);
  if (r.has("springs")) {
    const JsonReader s = r.at("springs");
    s.expect_object({"structural", "shear", "bend", "stiffness", "damping", "substep"});
    if (s.has("structural")) e.springs.structural = s.at("structural").boolean();
    if (s.has("shear")) e.springs.shear = s.at("shear").boolean();
    if (s.has("bend")) e.springs.bend = s.at("bend").boolean();
    if (s.has("stiffness")) e.springs.stiffness = s.at("stiffness").number(0.0f, big);
    if (s.has("damping")) e.springs.damping = s.at("damping").number(0.0f, big);
    if (s.has("substep")) e.springs.substep = s.at("substep").number(0.0f, 1.0f, true);
  }
  return e;
}

// A gravity vector, m/s², at most 1e6 long (require_valid_motion, require_valid_chain_settings).
glm::vec3 read_gravity(const JsonReader& r) {
  const glm::vec3 g = r.vec3();
  if (!(glm::length(g) <= 1e6f)) r.fail("must be at most 1e6 m/s² long");
  return g;
}

LatticeMotion read_motion(const JsonReader& r) {
  // The ranges require_valid_motion enforces (runtime/hierarchy.hpp).
  LatticeMotion motion;
  r.expect_object({"inertia", "gravity", "units_per_metre", "along_bound", "far_share", "part"});
  if (r.has("part")) {  // absent in files from before parts: unspecified, LatticeMotion's default
    const JsonReader part = r.at("part");
    const std::optional<BodyPart> named = body_part_named(part.text());
    if (!named)
      part.fail(
          "must be \"upper_limb\", \"lower_limb\", \"hand\", \"foot\", \"torso\", \"head\", \"appendage\" or "
          "\"unspecified\"");
    motion.part = *named;
  }
  if (r.has("inertia")) motion.inertia = r.at("inertia").number(0.0f, 1.0f);
  if (r.has("along_bound")) motion.along_bound = r.at("along_bound").number(0.0f, 1.0f);
  if (r.has("far_share")) motion.far_share = r.at("far_share").number(0.0f, 1.0f);
  if (r.has("gravity")) motion.gravity = read_gravity(r.at("gravity"));
  if (r.has("units_per_metre")) motion.units_per_metre = r.at("units_per_metre").number(0.0f, 1e6f, true);
  return motion;
}

// The "springs" block: colliders first, since chains name them by index.
void read_springs(const JsonReader& r, const Skeleton& skeleton, Rig& rig) {
  constexpr float big = 1e6f;  // the runtime's bound on lengths and units (require_valid_chain_settings)
  r.expect_object({"substep", "colliders", "chains"});
  if (r.has("substep")) rig.spring_substep = r.at("substep").number(0.0f, 1.0f, true);
  if (r.has("colliders")) {
    const JsonReader colliders = r.at("colliders");
    for (std::size_t i = 0; i < colliders.array_size(); ++i) {
      const JsonReader c = colliders.at(i);
      c.expect_object({"bone", "start", "end", "radius"});
      SpringCollider collider;
      collider.bone = read_bone(c.at("bone"), skeleton);
      collider.start = c.at("start").vec3();
      collider.end = c.has("end") ? c.at("end").vec3() : collider.start;
      collider.radius = c.at("radius").number(0.0f, big, true);
      rig.colliders.push_back(collider);
    }
  }
  if (!r.has("chains")) return;
  const JsonReader chains = r.at("chains");
  for (std::size_t i = 0; i < chains.array_size(); ++i) {
    const JsonReader c = chains.at(i);
    c.expect_object(
        {"name", "bones", "tip", "frequency", "damping_ratio", "gravity", "units_per_metre", "radius", "colliders"});
    SpringChainSpec chain;
    chain.name = c.at("name").text();
    if (chain.name.empty()) c.at("name").fail("must not be empty");
    for (const SpringChainSpec& other : rig.spring_chains)
      if (other.name == chain.name) c.at("name").fail("chain name '" + chain.name + "' is used twice");
    const JsonReader bones = c.at("bones");
    const std::size_t count = bones.array_size();
    if (count == 0) bones.fail("must name at least one bone");
    for (std::size_t b = 0; b < count; ++b) {
      chain.bones.push_back(read_bone(bones.at(b), skeleton));
      if (b > 0 && skeleton.bones()[std::size_t(chain.bones[b])].parent != chain.bones[b - 1])
        bones.at(b).fail("must be a child of the bone before it");
    }
    if (c.has("tip")) chain.tip = c.at("tip").vec3();
    if (c.has("frequency")) chain.frequency = c.at("frequency").number(0.0f, 1000.0f, true);
    if (c.has("damping_ratio")) chain.damping_ratio = c.at("damping_ratio").number(0.0f, 1000.0f);
    if (c.has("gravity")) chain.gravity = read_gravity(c.at("gravity"));
    if (c.has("units_per_metre")) chain.units_per_metre = c.at("units_per_metre").number(0.0f, big, true);
    if (c.has("radius")) chain.radius = c.at("radius").number(0.0f, big);
    if (c.has("colliders")) {
      const JsonReader list = c.at("colliders");
      for (std::size_t k = 0; k < list.array_size(); ++k) {
        const std::int64_t last = std::int64_t(rig.colliders.size()) - 1;
        if (last < 0) list.at(k).fail("names a collider, but the rig has none");
        chain.colliders.push_back(std::uint32_t(list.at(k).integer(0, last)));
      }
    }
    rig.spring_chains.push_back(std::move(chain));
  }
}

void read_correctives(const JsonReader& list, const Skeleton& skeleton, std::size_t point_count, Rig& rig) {
  for (std::size_t i = 0; i < list.array_size(); ++i) {
    const JsonReader c = list.at(i);
    c.expect_object({"name", "bones", "kernel", "radius", "twist_weight", "rest", "shapes"});
    CorrectiveSpec group;
    group.name = c.at("name").text();
    if (group.name.empty()) c.at("name").fail("must not be empty");
    for (const CorrectiveSpec& other : rig.correctives)
      if (other.name == group.name) c.at("name").fail("group name '" + group.name + "' is used twice");
    const JsonReader bones = c.at("bones");
    if (bones.array_size() == 0) bones.fail("must name at least one bone");
    for (std::size_t b = 0; b < bones.array_size(); ++b) {
      group.bones.push_back(read_bone(bones.at(b), skeleton));
      if (std::count(group.bones.begin(), group.bones.end(), group.bones.back()) > 1)
        bones.at(b).fail("is listed twice");
    }
    if (c.has("kernel")) {
      const std::string kernel = c.at("kernel").text();
      if (kernel == "gaussian") group.kernel = RbfKernel::gaussian;
      else if (kernel == "inverse_multiquadric") group.kernel = RbfKernel::inverse_multiquadric;
      else c.at("kernel").fail("must be \"gaussian\" or \"inverse_multiquadric\"");
    }
    if (c.has("radius")) group.radius = c.at("radius").number(0.0f, 1e6f);
    if (c.has("twist_weight")) group.twist_weight = c.at("twist_weight").number(0.0f, 1e6f);
    if (c.has("rest")) group.rest = c.at("rest").boolean();
    const JsonReader shapes = c.at("shapes");
    if (shapes.array_size() == 0) shapes.fail("must hold at least one shape");
    for (std::size_t k = 0; k < shapes.array_size(); ++k) {
      const JsonReader r = shapes.at(k);
      r.expect_object({"name", "pose", "points", "deltas"});
      CorrectiveShape shape;
      shape.name = r.at("name").text();
      const JsonReader pose = r.at("pose");
      if (pose.array_size() != group.bones.size()) pose.fail("must give one rotation per driver bone");
      for (std::size_t b = 0; b < group.bones.size(); ++b) shape.pose.push_back(pose.at(b).vec3());
      const JsonReader points = r.at("points"), deltas = r.at("deltas");
      if (points.array_size() > point_count) points.fail("lists more points than the mesh has");
      if (deltas.array_size() != points.array_size()) deltas.fail("must give one delta per point");
      for (std::size_t v = 0; v < points.array_size(); ++v) {
        const auto index = std::uint32_t(points.at(v).integer(0, std::int64_t(point_count) - 1));
        if (!shape.points.empty() && index <= shape.points.back())
          points.at(v).fail("points must be strictly ascending");
        shape.points.push_back(index);
        shape.deltas.push_back(deltas.at(v).vec3());
      }
      group.shapes.push_back(std::move(shape));
    }
    rig.correctives.push_back(std::move(group));
  }
}

ojson vec3_json(glm::vec3 v) {
  return ojson::array({shortest_double(v.x), shortest_double(v.y), shortest_double(v.z)});
}

RigModel read_model(const JsonReader& root) {
  RigModel model;
  if (!root.has("model") || root.at("model").is_null()) return model;
  const JsonReader r = root.at("model");
  if (r.is_string()) {
    if (r.text() != "builtin")
      r.fail("must be \"builtin\", {\"file\": MODEL} or an object with obj, skeleton and weights");
    model.builtin = true;
    return model;
  }
  r.expect_object({"obj", "skeleton", "weights", "file"});
  if (r.has("file")) {  // an imported model: nothing else with it
    if (r.has("obj") || r.has("skeleton") || r.has("weights")) r.fail("has \"file\" and native files: give one");
    model.file = r.at("file").text();
    if (model.file.empty()) r.at("file").fail("must not be empty");
    return model;
  }
  model.obj = r.at("obj").text();
  model.skeleton = r.at("skeleton").text();
  model.weights = r.at("weights").text();
  return model;
}

}  // namespace

RigModel parse_rig_model(std::string_view text, const std::string& name) {
  const json document = detail::parse_json(text, name);
  const JsonReader root(name, document, "");
  if (!document.is_object()) root.fail("must be an object");
  return read_model(root);
}

Rig parse_rig_json(std::string_view text, const Skeleton& skeleton, std::size_t point_count, const std::string& name) {
  const json document = detail::parse_json(text, name);
  const JsonReader root(name, document, "");
  root.expect_object({"rig", "model", "reach", "lattices", "springs", "correctives"});
  if (root.at("rig").integer(1, 1) != rig_format_version) root.at("rig").fail("unsupported version");
  Rig rig;
  rig.model = read_model(root);
  if (root.has("reach")) {
    const JsonReader reach = root.at("reach");
    reach.expect_object({"effector", "root", "max_stretch", "chains"});
    if (reach.has("effector") && !reach.at("effector").is_null())
      rig.reach_effector = read_bone(reach.at("effector"), skeleton);
    if (reach.has("root") && !reach.at("root").is_null()) rig.reach_root = read_bone(reach.at("root"), skeleton);
    if (reach.has("max_stretch")) rig.max_stretch = reach.at("max_stretch").number(0.0f, 1000.0f);
    if (rig.reach_root >= 0 && (rig.reach_effector < 0 || rig.reach_root == rig.reach_effector ||
                                !skeleton.is_ancestor(rig.reach_root, rig.reach_effector))) {
      reach.at("root").fail("must be a proper ancestor of the effector");
    }
    if (reach.has("chains")) {
      const JsonReader chains = reach.at("chains");
      for (std::size_t i = 0; i < chains.array_size(); ++i) {
        const JsonReader c = chains.at(i);
        c.expect_object({"effector", "root"});
        Rig::ReachChain chain{read_bone(c.at("effector"), skeleton), read_bone(c.at("root"), skeleton)};
        if (chain.root == chain.effector || !skeleton.is_ancestor(chain.root, chain.effector))
          c.at("root").fail("must be a proper ancestor of the effector");
        for (const Rig::ReachChain& other : rig.reach_chains)
          if (other.effector == chain.effector) c.at("effector").fail("has a chain already");
        if (chain.effector == rig.reach_effector)
          c.at("effector").fail("is the reach effector: its root is reach.root");
        rig.reach_chains.push_back(chain);
      }
    }
  }
  const JsonReader lattices = root.at("lattices");
  const std::size_t count = lattices.array_size();
  std::vector<std::string> parents(count);
  for (std::size_t i = 0; i < count; ++i) {
    const JsonReader r = lattices.at(i);
    r.expect_object({"name", "bone", "parent", "degree", "select", "margin", "carry", "min_length_fraction", "volume",
                     "motion", "elastic"});
    LatticeSpec spec;
    spec.name = r.at("name").text();
    if (spec.name.empty()) r.at("name").fail("must not be empty");
    for (const LatticeSpec& other : rig.lattices) {
      if (other.name == spec.name) r.at("name").fail("lattice name '" + spec.name + "' is used twice");
    }
    spec.bone = read_bone(r.at("bone"), skeleton);
    if (r.has("parent")) parents[i] = r.at("parent").is_null() ? "" : r.at("parent").text();
    if (r.has("degree")) {
      spec.degree = r.at("degree").ivec3(glm::ivec3(1), glm::ivec3(max_bezier_degree));
    }
    if (r.has("select")) {
      const JsonReader select = r.at("select");
      select.expect_object({"by", "threshold", "vertices"});
      const std::string by = select.at("by").text();
      if (by == "weight") {
        spec.selection = VertexSelection::subtree_weight;
        if (select.has("vertices")) select.at("vertices").fail("only with \"by\": \"list\"");
        if (select.has("threshold")) spec.weight_threshold = select.at("threshold").number(0.0f, 0.99999994f);
      } else if (by == "list") {
        spec.selection = VertexSelection::list;
        if (select.has("threshold")) select.at("threshold").fail("only with \"by\": \"weight\"");
        const JsonReader vertices = select.at("vertices");
        const std::size_t n = vertices.array_size();
        if (n > point_count) vertices.fail("lists more vertices than the mesh has");
        std::vector<std::uint8_t> seen(point_count, 0);
        for (std::size_t v = 0; v < n; ++v) {
          const auto index = std::uint32_t(vertices.at(v).integer(0, std::int64_t(point_count) - 1));
          if (seen[index]) vertices.at(v).fail("vertex " + std::to_string(index) + " is listed twice");
          seen[index] = 1;
          spec.vertices.push_back(index);
        }
        std::sort(spec.vertices.begin(), spec.vertices.end());
      } else {
        select.at("by").fail("must be \"weight\" or \"list\"");
      }
    }
    if (r.has("margin")) spec.margin = r.at("margin").number(0.0f, 1.0f);
    if (r.has("carry")) spec.carry_descendants = r.at("carry").boolean();
    // The ranges require_valid_shape enforces (runtime/hierarchy.hpp); the floor must stay below the full length.
    if (r.has("min_length_fraction")) {
      const JsonReader floor = r.at("min_length_fraction");
      spec.shape.min_length_fraction = floor.number(0.0f, 1.0f);
      if (!(spec.shape.min_length_fraction < 1.0f)) floor.fail("must be in [0, 1)");
    }
    if (r.has("volume")) spec.shape.volume = r.at("volume").number(0.0f, 1.0f);
    if (r.has("motion")) spec.motion = read_motion(r.at("motion"));
    if (r.has("elastic")) spec.elastic = read_elastic(r.at("elastic"));
    rig.lattices.push_back(std::move(spec));
  }
  for (std::size_t i = 0; i < count; ++i) {
    if (!lattices.at(i).has("parent")) continue;
    const std::int32_t implied = implied_parent(rig.lattices, skeleton, i);
    const std::string expected = implied < 0 ? "" : rig.lattices[std::size_t(implied)].name;
    if (parents[i] != expected) {
      lattices.at(i).at("parent").fail("the bones make the parent " +
                                       (expected.empty() ? std::string("null") : "'" + expected + "'"));
    }
  }
  if (root.has("springs")) read_springs(root.at("springs"), skeleton, rig);
  if (root.has("correctives")) read_correctives(root.at("correctives"), skeleton, point_count, rig);
  return rig;
}

Rig read_rig_json(const std::string& path, const Skeleton& skeleton, std::size_t point_count) {
  return parse_rig_json(read_file_text(path), skeleton, point_count, path);
}

std::string format_rig_json(const Rig& rig, const Skeleton& skeleton) {
  ojson document = ojson::object();
  document["rig"] = rig_format_version;
  if (rig.model.builtin) {
    document["model"] = "builtin";
  } else if (!rig.model.file.empty()) {
    document["model"] = {{"file", rig.model.file}};
  } else if (!rig.model.obj.empty() || !rig.model.skeleton.empty() || !rig.model.weights.empty()) {
    document["model"] = {{"obj", rig.model.obj}, {"skeleton", rig.model.skeleton}, {"weights", rig.model.weights}};
  }
  document["reach"] = {{"effector", rig.reach_effector < 0 ? ojson(nullptr) : ojson(skeleton.key(rig.reach_effector))},
                       {"root", rig.reach_root < 0 ? ojson(nullptr) : ojson(skeleton.key(rig.reach_root))},
                       {"max_stretch", shortest_double(rig.max_stretch)}};
  if (!rig.reach_chains.empty()) {  // written only when there are some: rigs without keep their old text
    ojson chains = ojson::array();
    for (const Rig::ReachChain& c : rig.reach_chains)
      chains.push_back({{"effector", skeleton.key(c.effector)}, {"root", skeleton.key(c.root)}});
    document["reach"]["chains"] = std::move(chains);
  }
  ojson lattices = ojson::array();
  for (std::size_t i = 0; i < rig.lattices.size(); ++i) {
    const LatticeSpec& spec = rig.lattices[i];
    const std::int32_t parent = implied_parent(rig.lattices, skeleton, i);
    ojson select = spec.selection == VertexSelection::list
                       ? ojson{{"by", "list"}, {"vertices", spec.vertices}}
                       : ojson{{"by", "weight"}, {"threshold", shortest_double(spec.weight_threshold)}};
    const ElasticSettings& e = spec.elastic;
    ojson elastic = {{"stiffness", shortest_double(e.oscillator.stiffness)},
                     {"damping_ratio", shortest_double(e.oscillator.damping_ratio)},
                     {"mass", shortest_double(e.oscillator.mass)},
                     {"integrator", e.integrator == Integrator::exact ? "exact" : "verlet"},
                     {"verlet_kd", shortest_double(e.verlet_kd)},
                     {"springs",
                      {{"structural", e.springs.structural},
                       {"shear", e.springs.shear},
                       {"bend", e.springs.bend},
                       {"stiffness", shortest_double(e.springs.stiffness)},
                       {"damping", shortest_double(e.springs.damping)},
                       {"substep", shortest_double(e.springs.substep)}}}};
    lattices.push_back({{"name", spec.name},
                        {"bone", skeleton.key(spec.bone)},
                        {"parent", parent < 0 ? ojson(nullptr) : ojson(rig.lattices[std::size_t(parent)].name)},
                        {"degree", {spec.degree.x, spec.degree.y, spec.degree.z}},
                        {"select", select},
                        {"margin", shortest_double(spec.margin)},
                        {"carry", spec.carry_descendants}});
    // The stretch shape only where it differs from the default, so rig files written before it existed (all of
    // them default) are written back byte for byte.
    const StretchShape default_shape;
    ojson& written = lattices.back();
    if (spec.shape.min_length_fraction != default_shape.min_length_fraction)
      written["min_length_fraction"] = shortest_double(spec.shape.min_length_fraction);
    if (spec.shape.volume != default_shape.volume) written["volume"] = shortest_double(spec.shape.volume);
    if (spec.motion != LatticeMotion{}) {  // likewise
      written["motion"] = {{"inertia", shortest_double(spec.motion.inertia)},
                           {"gravity", vec3_json(spec.motion.gravity)},
                           {"units_per_metre", shortest_double(spec.motion.units_per_metre)},
                           {"along_bound", shortest_double(spec.motion.along_bound)},
                           {"far_share", shortest_double(spec.motion.far_share)}};
      if (spec.motion.part != BodyPart::unspecified)  // files from before parts are written back as they were
        written["motion"]["part"] = std::string(body_part_name(spec.motion.part));
    }
    written["elastic"] = elastic;
  }
  document["lattices"] = lattices;
  // Written when there are chains or colliders, or a substep of its own (which would otherwise be lost on a read back).
  if (!rig.spring_chains.empty() || !rig.colliders.empty() || rig.spring_substep != SpringChains::default_substep) {
    ojson colliders = ojson::array();
    for (const SpringCollider& c : rig.colliders) {
      colliders.push_back({{"bone", skeleton.key(c.bone)},
                           {"start", vec3_json(c.start)},
                           {"end", vec3_json(c.end)},
                           {"radius", shortest_double(c.radius)}});
    }
    ojson chains = ojson::array();
    for (const SpringChainSpec& c : rig.spring_chains) {
      ojson bones = ojson::array();
      for (const std::int32_t b : c.bones) bones.push_back(skeleton.key(b));
      chains.push_back({{"name", c.name},
                        {"bones", bones},
                        {"tip", vec3_json(c.tip)},
                        {"frequency", shortest_double(c.frequency)},
                        {"damping_ratio", shortest_double(c.damping_ratio)},
                        {"gravity", vec3_json(c.gravity)},
                        {"units_per_metre", shortest_double(c.units_per_metre)},
                        {"radius", shortest_double(c.radius)},
                        {"colliders", c.colliders}});
    }
    document["springs"] = {
        {"substep", shortest_double(rig.spring_substep)}, {"colliders", colliders}, {"chains", chains}};
  }
  if (!rig.correctives.empty()) {  // written only when there are some: rigs without keep their old text
    ojson groups = ojson::array();
    for (const CorrectiveSpec& group : rig.correctives) {
      ojson bones = ojson::array(), shapes = ojson::array();
      for (const std::int32_t b : group.bones) bones.push_back(skeleton.key(b));
      for (const CorrectiveShape& shape : group.shapes) {
        ojson pose = ojson::array(), deltas = ojson::array();
        for (const glm::vec3& angles : shape.pose) pose.push_back(vec3_json(angles));
        for (const glm::vec3& delta : shape.deltas) deltas.push_back(vec3_json(delta));
        shapes.push_back({{"name", shape.name}, {"pose", pose}, {"points", shape.points}, {"deltas", deltas}});
      }
      groups.push_back({{"name", group.name},
                        {"bones", bones},
                        {"kernel", group.kernel == RbfKernel::gaussian ? "gaussian" : "inverse_multiquadric"},
                        {"radius", shortest_double(group.radius)},
                        {"twist_weight", shortest_double(group.twist_weight)},
                        {"rest", group.rest},
                        {"shapes", shapes}});
    }
    document["correctives"] = std::move(groups);
  }
  return document.dump(2) + "\n";
}

void write_rig_json(const std::string& path, const Rig& rig, const Skeleton& skeleton) {
  write_file_atomic(path, format_rig_json(rig, skeleton));
}

}  // namespace deform
