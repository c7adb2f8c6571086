// The rigger's controls over skin weights (weight_tools.hpp): bone selection by glob, and the weight tools.
#include "deform/offline/weight_tools.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <limits>
#include <numeric>
#include <unordered_map>

#include "deform/offline/topology.hpp"
#include "deform/runtime/error.hpp"
namespace deform {
namespace {

[[noreturn]] void bad_pattern(std::string_view pattern, const char* why) {
  throw Error::invalid_argument("pattern '" + std::string(pattern) + "'", why);
}

// The length of the UTF-8 character starting at name[i] (a continuation byte or a truncated sequence counts 1).
std::size_t character_length(std::string_view name, std::size_t i) {
  const auto lead = static_cast<unsigned char>(name[i]);
  const std::size_t length = lead < 0xC0 ? 1 : lead < 0xE0 ? 2 : lead < 0xF0 ? 3 : 4;
  std::size_t n = 1;
  while (n < length && i + n < name.size() && (static_cast<unsigned char>(name[i + n]) & 0xC0) == 0x80) ++n;
  return n;
}

// Matches the bracket expression starting at pattern[p] == '[' against byte c; sets `end` past its `]`.
bool bracket_matches(std::string_view pattern, std::size_t p, unsigned char c, std::size_t& end) {
  std::size_t i = p + 1;
  bool negate = false;
  if (i < pattern.size() && (pattern[i] == '!' || pattern[i] == '^')) {
    negate = true;
    ++i;
  }
  bool found = false;
  bool first = true;
  while (true) {
    if (i >= pattern.size()) bad_pattern(pattern, "unclosed '['");
    if (pattern[i] == ']' && !first) break;
    first = false;
    unsigned char lo = static_cast<unsigned char>(pattern[i]);
    if (lo == '\\') {
      if (++i >= pattern.size()) bad_pattern(pattern, "ends with '\\'");
      lo = static_cast<unsigned char>(pattern[i]);
    }
    unsigned char hi = lo;
    if (i + 2 < pattern.size() && pattern[i + 1] == '-' && pattern[i + 2] != ']') {
      i += 2;
      hi = static_cast<unsigned char>(pattern[i]);
      if (hi == '\\') {
        if (++i >= pattern.size()) bad_pattern(pattern, "ends with '\\'");
        hi = static_cast<unsigned char>(pattern[i]);
      }
    }
    if (lo <= c && c <= hi) found = true;
    ++i;
  }
  end = i + 1;
  return found != negate;
}

// Checks the pattern's syntax once (so that an error does not depend on the names it is matched against).
void check_pattern(std::string_view pattern) {
  for (std::size_t i = 0; i < pattern.size(); ++i) {
    if (pattern[i] == '\\') {
      if (i + 1 >= pattern.size()) bad_pattern(pattern, "ends with '\\'");
      ++i;
    } else if (pattern[i] == '[') {
      std::size_t end = 0;
      bracket_matches(pattern, i, 0, end);
      i = end - 1;
    }
  }
}

bool match_from(std::string_view pattern, std::size_t p, std::string_view name, std::size_t n) {
  // Iterative with one backtracking point (the last `*`): O(|pattern| · |name|).
  std::size_t star_p = std::string_view::npos, star_n = 0;
  while (n < name.size()) {
    if (p < pattern.size()) {
      const char c = pattern[p];
      if (c == '*') {
        star_p = p++;
        star_n = n;
        continue;
      }
      if (c == '?') {
        n += character_length(name, n);
        ++p;
        continue;
      }
      if (c == '[') {
        std::size_t end = 0;
        if (bracket_matches(pattern, p, static_cast<unsigned char>(name[n]), end)) {
          p = end;
          ++n;
          continue;
        }
      } else {
        const char literal = c == '\\' && p + 1 < pattern.size() ? pattern[p + 1] : c;
        if (c == '\\' && p + 1 >= pattern.size()) bad_pattern(pattern, "ends with '\\'");
        if (literal == name[n]) {
          p += c == '\\' ? 2 : 1;
          ++n;
          continue;
        }
      }
    }
    if (star_p == std::string_view::npos) return false;
    p = star_p + 1;
    n = ++star_n;
  }
  while (p < pattern.size() && pattern[p] == '*') ++p;
  return p == pattern.size();
}

// Influences of every point as compressed rows (slots then extras, positive weights only).
struct Rows {
  std::vector<std::uint32_t> offsets{0};
  std::vector<std::uint16_t> bones;
  std::vector<float> weights;
  std::size_t size() const { return offsets.size() - 1; }
  std::size_t begin(std::size_t p) const { return offsets[p]; }
  std::size_t end(std::size_t p) const { return offsets[p + 1]; }
};

// Throws deform::Error (kind argument) for weights whose arrays disagree or hold a negative or non-finite weight.
void check_weights(const SkinWeights& w) {
  auto fail = [](const std::string& element, const std::string& why) { throw Error::invalid_argument(element, why); };
  if (w.weights.size() != w.bones.size()) fail("weights", "hold a different number of bone and weight slots");
  if (w.extra_bones.size() != w.extra_weights.size()) fail("weights", "extras: bones and weights differ in count");
  if (!w.extra_points.empty() || !w.extra_offsets.empty()) {
    if (w.extra_offsets.size() != w.extra_points.size() + 1 || w.extra_offsets.front() != 0 ||
        w.extra_offsets.back() != w.extra_bones.size())
      fail("weights", "extras: offsets do not match the points and influences");
    for (std::size_t j = 0; j < w.extra_points.size(); ++j)
      if (w.extra_points[j] >= w.size() || (j > 0 && w.extra_points[j] <= w.extra_points[j - 1]) ||
          w.extra_offsets[j + 1] < w.extra_offsets[j])
        fail("weights", "extras: points out of range or order");
  }
  auto check_value = [&](std::size_t point, float value) {
    if (!std::isfinite(value) || value < 0.0f)
      fail("point " + std::to_string(point), "weight " + std::to_string(value) + " is negative or not finite");
  };
  for (std::size_t p = 0; p < w.size(); ++p)
    for (int k = 0; k < max_influences; ++k) check_value(p, w.weights[p][k]);
  for (std::size_t j = 0; j < w.extra_points.size(); ++j)
    for (std::uint32_t e = w.extra_offsets[j]; e < w.extra_offsets[j + 1]; ++e)
      check_value(w.extra_points[j], w.extra_weights[e]);
}

Rows to_rows(const SkinWeights& w) {
  check_weights(w);
  Rows rows;
  rows.offsets.reserve(w.size() + 1);
  std::size_t extra = 0;
  for (std::size_t p = 0; p < w.size(); ++p) {
    for (int k = 0; k < max_influences; ++k)
      if (w.weights[p][k] > 0.0f) {
        rows.bones.push_back(w.bones[p][k]);
        rows.weights.push_back(w.weights[p][k]);
      }
    if (extra < w.extra_points.size() && w.extra_points[extra] == p) {
      for (std::uint32_t e = w.extra_offsets[extra]; e < w.extra_offsets[extra + 1]; ++e)
        if (w.extra_weights[e] > 0.0f) {
          rows.bones.push_back(w.extra_bones[e]);
          rows.weights.push_back(w.extra_weights[e]);
        }
      ++extra;
    }
    rows.offsets.push_back(static_cast<std::uint32_t>(rows.bones.size()));
  }
  return rows;
}

// One point's influences, strongest first (ties: the lower bone), as append_influences orders them.
using Influences = std::vector<std::pair<std::uint16_t, float>>;
void sort_strongest_first(Influences& row) {
  std::sort(row.begin(), row.end(), [](const auto& a, const auto& b) {
    return a.second != b.second ? a.second > b.second : a.first < b.first;
  });
}

void append(SkinWeights& out, const Influences& row) {
  std::vector<std::uint16_t> bones(row.size());
  std::vector<float> values(row.size());
  for (std::size_t i = 0; i < row.size(); ++i) {
    bones[i] = row[i].first;
    values[i] = row[i].second;
  }
  append_influences(out, bones, values);
}

// Applies `edit` to each point's influences (normalised, strongest first) and rebuilds the weights.
template <typename Edit>
void edit_rows(SkinWeights& weights, Edit edit) {
  const Rows rows = to_rows(weights);
  SkinWeights out;
  out.bones.reserve(rows.size());
  out.weights.reserve(rows.size());
  Influences row;
  for (std::size_t p = 0; p < rows.size(); ++p) {
    row.clear();
    double sum = 0.0;
    for (std::size_t i = rows.begin(p); i < rows.end(p); ++i) {
      row.emplace_back(rows.bones[i], rows.weights[i]);
      sum += rows.weights[i];
    }
    if (sum > 0.0)
      for (auto& [bone, w] : row) w = static_cast<float>(w / sum);
    sort_strongest_first(row);
    edit(row);
    append(out, row);
  }
  weights = std::move(out);
}

// Points welded by exact position: `vertex[p]` and the vertex count.
std::vector<std::uint32_t> weld_points(const Mesh& mesh, std::uint32_t& vertex_count) {
  const std::size_t n = mesh.positions.size();
  std::vector<std::uint32_t> order(n);
  std::iota(order.begin(), order.end(), 0u);
  auto key = [&](std::uint32_t i) {
    const glm::vec3 v = mesh.positions[i];
    return std::array<float, 3>{v.x, v.y, v.z};
  };
  std::sort(order.begin(), order.end(), [&](std::uint32_t a, std::uint32_t b) {
    const auto ka = key(a), kb = key(b);
    return ka != kb ? ka < kb : a < b;
  });
  std::vector<std::uint32_t> vertex(n);
  vertex_count = 0;
  for (std::size_t i = 0; i < n; ++i) {
    if (i > 0 && key(order[i]) != key(order[i - 1])) ++vertex_count;
    vertex[order[i]] = vertex_count;
  }
  if (n > 0) ++vertex_count;
  return vertex;
}

// The welded vertices' neighbours as compressed rows (ascending, no duplicates, never the vertex itself).
struct Graph {
  std::vector<std::uint32_t> offsets, neighbours;
};

Graph welded_graph(const Mesh& mesh, const std::vector<std::uint32_t>& vertex, std::uint32_t vertex_count) {
  const PointTopology topology = build_point_topology(mesh);
  std::vector<std::pair<std::uint32_t, std::uint32_t>> edges;
  for (std::uint32_t p = 0; p + 1 < topology.neighbour_offsets.size(); ++p)
    for (std::uint32_t q : topology.point_neighbours(p))
      if (vertex[p] != vertex[q]) edges.emplace_back(vertex[p], vertex[q]);
  std::sort(edges.begin(), edges.end());
  edges.erase(std::unique(edges.begin(), edges.end()), edges.end());
  Graph g;
  g.offsets.assign(vertex_count + 1, 0);
  for (const auto& e : edges) ++g.offsets[e.first + 1];
  for (std::uint32_t v = 0; v < vertex_count; ++v) g.offsets[v + 1] += g.offsets[v];
  g.neighbours.reserve(edges.size());
  for (const auto& e : edges) g.neighbours.push_back(e.second);
  return g;
}

void check_weights_fit(const SkinWeights& weights, const Mesh& mesh) {
  if (weights.size() != mesh.point_count())
    throw Error::invalid_argument("weights", "hold " + std::to_string(weights.size()) + " points, the mesh " +
                                                 std::to_string(mesh.point_count()));
}

// Per welded vertex, the mean of its points' normalised influences, as dense-merged rows sorted by bone.
struct VertexRows {
  std::vector<std::uint32_t> offsets;
  std::vector<std::uint16_t> bones;
  std::vector<float> weights;
};

// Merges per-vertex contributions with a dense scratch over the bones. `add(v, accumulate)` calls accumulate(bone,
// weight) for everything vertex v gets.
template <typename Add>
VertexRows merge_rows(std::uint32_t vertex_count, std::size_t bone_count, Add add) {
  VertexRows out;
  out.offsets.reserve(vertex_count + 1);
  out.offsets.push_back(0);
  std::vector<double> dense(bone_count, 0.0);
  std::vector<std::uint16_t> touched;
  for (std::uint32_t v = 0; v < vertex_count; ++v) {
    touched.clear();
    add(v, [&](std::uint16_t bone, double w) {
      if (dense[bone] == 0.0) touched.push_back(bone);
      dense[bone] += w;
      if (dense[bone] == 0.0) dense[bone] = std::numeric_limits<double>::min();  // keep it marked as touched
    });
    std::sort(touched.begin(), touched.end());
    for (std::uint16_t bone : touched) {
      if (dense[bone] > std::numeric_limits<double>::min()) {
        out.bones.push_back(bone);
        out.weights.push_back(static_cast<float>(dense[bone]));
      }
      dense[bone] = 0.0;
    }
    out.offsets.push_back(static_cast<std::uint32_t>(out.bones.size()));
  }
  return out;
}

std::size_t bone_bound(const Rows& rows) {
  std::size_t most = 0;
  for (std::uint16_t b : rows.bones) most = std::max<std::size_t>(most, b + 1u);
  return most;
}

// The starting vertex rows of smoothing and the energy: each welded vertex the mean of its points' normalised rows.
VertexRows welded_rows(const Rows& rows, const std::vector<std::uint32_t>& vertex, std::uint32_t vertex_count) {
  std::vector<std::uint32_t> point_offsets(vertex_count + 1, 0), points(vertex.size());
  for (std::uint32_t v : vertex) ++point_offsets[v + 1];
  for (std::uint32_t v = 0; v < vertex_count; ++v) point_offsets[v + 1] += point_offsets[v];
  std::vector<std::uint32_t> fill(point_offsets.begin(), point_offsets.end() - 1);
  for (std::uint32_t p = 0; p < vertex.size(); ++p) points[fill[vertex[p]]++] = p;
  return merge_rows(vertex_count, bone_bound(rows), [&](std::uint32_t v, auto accumulate) {
    const double share = 1.0 / double(point_offsets[v + 1] - point_offsets[v]);
    for (std::uint32_t k = point_offsets[v]; k < point_offsets[v + 1]; ++k) {
      const std::uint32_t p = points[k];
      double sum = 0.0;
      for (std::size_t i = rows.begin(p); i < rows.end(p); ++i) sum += rows.weights[i];
      if (sum <= 0.0) continue;
      for (std::size_t i = rows.begin(p); i < rows.end(p); ++i)
        accumulate(rows.bones[i], share * rows.weights[i] / sum);
    }
  });
}

bool is_separator(char c) { return c == '.' || c == '_' || c == '-' || c == ' '; }
bool is_lower(char c) { return c >= 'a' && c <= 'z'; }
bool is_upper(char c) { return c >= 'A' && c <= 'Z'; }
bool is_letter(char c) { return is_lower(c) || is_upper(c); }

// The built-in side token at name[i], if any: its length and its swapped text.
std::optional<std::pair<std::size_t, const char*>> side_token(std::string_view name, std::size_t i) {
  const char before = i > 0 ? name[i - 1] : '\0';
  auto after = [&](std::size_t length) { return i + length < name.size() ? name[i + length] : '\0'; };
  // L / R / l / r alone between separators (at least one of them a real separator, so a bone named "L" has none).
  const char c = name[i];
  if (c == 'L' || c == 'R' || c == 'l' || c == 'r') {
    const char next = after(1);
    const bool left_edge = i == 0 || is_separator(before);
    const bool right_edge = next == '\0' || is_separator(next);
    if (left_edge && right_edge && (i > 0 || next != '\0')) {
      static const char* const swapped[] = {"R", "L", "r", "l"};
      return std::make_pair(std::size_t{1}, swapped[c == 'L' ? 0 : c == 'R' ? 1 : c == 'l' ? 2 : 3]);
    }
  }
  struct Word {
    const char* text;
    const char* swapped;
    int form;  // 0 capitalised, 1 upper, 2 lower
  };
  static const Word words[] = {{"Left", "Right", 0}, {"Right", "Left", 0}, {"LEFT", "RIGHT", 1},
                               {"RIGHT", "LEFT", 1}, {"left", "right", 2}, {"right", "left", 2}};
  for (const Word& w : words) {
    const std::string_view text = w.text;
    if (name.substr(i, text.size()) != text) continue;
    const char next = after(text.size());
    bool starts = false, ends = false;
    if (w.form == 0) {
      starts = i == 0 || !is_letter(before) || is_lower(before);
      ends = !is_lower(next);
    } else if (w.form == 1) {
      starts = i == 0 || !is_upper(before);
      ends = !is_upper(next);
    } else {
      starts = i == 0 || !is_letter(before);
      ends = !is_lower(next);
    }
    if (starts && ends) return std::make_pair(text.size(), w.swapped);
  }
  return std::nullopt;
}

// A bone's label in messages, as the weight methods write it.
std::string label(const Skeleton& skeleton, std::size_t bone) {
  return "bone '" + skeleton.bone(static_cast<std::int32_t>(bone)).name + "' (id " + std::to_string(bone) + ")";
}

std::string format_point(glm::vec3 p) {
  char text[96];
  std::snprintf(text, sizeof text, "(%.6g, %.6g, %.6g)", double(p.x), double(p.y), double(p.z));
  return text;
}

}  // namespace

bool glob_match(std::string_view pattern, std::string_view name) {
  check_pattern(pattern);
  return match_from(pattern, 0, name, 0);
}

std::vector<std::uint8_t> select_bones(const Skeleton& skeleton, std::span<const std::string> include,
                                       std::span<const std::string> exclude, std::span<const std::uint8_t> also) {
  const std::size_t n = skeleton.bone_count();
  if (!also.empty() && also.size() != n) throw Error::invalid_argument("also", "must be empty or one entry per bone");
  auto matches = [&](const std::string& pattern) {
    check_pattern(pattern);
    std::vector<std::uint8_t> hit(n, 0);
    bool any = false;
    for (std::size_t b = 0; b < n; ++b)
      if (match_from(pattern, 0, skeleton.bone(static_cast<std::int32_t>(b)).name, 0)) hit[b] = 1, any = true;
    if (!any) bad_pattern(pattern, "matches no bone");
    return hit;
  };
  std::vector<std::uint8_t> mask(n, include.empty() && also.empty() ? 1 : 0);
  for (std::size_t b = 0; b < also.size(); ++b) mask[b] = also[b] != 0 ? 1 : 0;
  for (const std::string& pattern : include) {
    const auto hit = matches(pattern);
    for (std::size_t b = 0; b < n; ++b) mask[b] |= hit[b];
  }
  for (const std::string& pattern : exclude) {
    const auto hit = matches(pattern);
    for (std::size_t b = 0; b < n; ++b)
      if (hit[b]) mask[b] = 0;
  }
  if (std::none_of(mask.begin(), mask.end(), [](std::uint8_t m) { return m != 0; }))
    throw Error::invalid_argument("bones", "no bone deforms");
  return mask;
}

std::vector<std::uint8_t> weighted_bones(const SkinWeights& weights, std::size_t bone_count) {
  std::vector<std::uint8_t> used(bone_count, 0);
  for (std::size_t p = 0; p < weights.size(); ++p)
    for (int k = 0; k < max_influences; ++k)
      if (weights.weights[p][k] > 0.0f && weights.bones[p][k] < bone_count) used[weights.bones[p][k]] = 1;
  for (std::size_t e = 0; e < weights.extra_bones.size() && e < weights.extra_weights.size(); ++e)
    if (weights.extra_weights[e] > 0.0f && weights.extra_bones[e] < bone_count) used[weights.extra_bones[e]] = 1;
  return used;
}

void normalize_weights(SkinWeights& weights) {
  edit_rows(weights, [](Influences&) {});
}

std::size_t prune_weights(SkinWeights& weights, float threshold) {
  if (!(threshold >= 0.0f && threshold <= 1.0f)) throw Error::invalid_argument("threshold", "must be 0 to 1");
  std::size_t removed = 0;
  edit_rows(weights, [&](Influences& row) {
    if (row.empty()) return;
    std::size_t keep = 0;
    while (keep < row.size() && row[keep].second >= threshold) ++keep;
    keep = std::max<std::size_t>(keep, 1);  // the strongest stays
    removed += row.size() - keep;
    row.resize(keep);
  });
  return removed;
}

std::size_t limit_influences(SkinWeights& weights, int count) {
  if (count < 1 || count > max_requested_influences)
    throw Error::invalid_argument("count", "must be 1 to " + std::to_string(max_requested_influences));
  std::size_t points = 0;
  edit_rows(weights, [&](Influences& row) {
    if (row.size() <= static_cast<std::size_t>(count)) return;
    row.resize(static_cast<std::size_t>(count));
    ++points;
  });
  return points;
}

void smooth_weights(SkinWeights& weights, const Mesh& mesh, const SmoothWeightsOptions& options) {
  if (options.iterations < 0 || options.iterations > 1000)
    throw Error::invalid_argument("iterations", "must be 0 to 1000");
  if (!(options.factor > 0.0f && options.factor <= 1.0f)) throw Error::invalid_argument("factor", "must be in (0, 1]");
  if (options.max_influences < 1 || options.max_influences > max_requested_influences)
    throw Error::invalid_argument("max_influences", "must be 1 to " + std::to_string(max_requested_influences));
  check_weights_fit(weights, mesh);
  std::uint32_t vertex_count = 0;
  const std::vector<std::uint32_t> vertex = weld_points(mesh, vertex_count);
  const Graph graph = welded_graph(mesh, vertex, vertex_count);
  const Rows rows = to_rows(weights);
  const std::size_t bone_count = bone_bound(rows);
  VertexRows current = welded_rows(rows, vertex, vertex_count);
  const double f = options.factor;
  for (int pass = 0; pass < options.iterations; ++pass) {
    current = merge_rows(vertex_count, bone_count, [&](std::uint32_t v, auto accumulate) {
      const std::uint32_t first = graph.offsets[v], last = graph.offsets[v + 1];
      const double own = first == last ? 1.0 : 1.0 - f;
      for (std::uint32_t i = current.offsets[v]; i < current.offsets[v + 1]; ++i)
        accumulate(current.bones[i], own * current.weights[i]);
      if (first == last) return;
      const double share = f / double(last - first);
      for (std::uint32_t k = first; k < last; ++k) {
        const std::uint32_t u = graph.neighbours[k];
        for (std::uint32_t i = current.offsets[u]; i < current.offsets[u + 1]; ++i)
          accumulate(current.bones[i], share * current.weights[i]);
      }
    });
  }
  SkinWeights out;
  Influences row;
  for (std::size_t p = 0; p < vertex.size(); ++p) {
    const std::uint32_t v = vertex[p];
    row.clear();
    for (std::uint32_t i = current.offsets[v]; i < current.offsets[v + 1]; ++i)
      row.emplace_back(current.bones[i], current.weights[i]);
    sort_strongest_first(row);
    if (row.size() > static_cast<std::size_t>(options.max_influences))
      row.resize(static_cast<std::size_t>(options.max_influences));
    append(out, row);
  }
  weights = std::move(out);
}

double weight_gradient_energy(const SkinWeights& weights, const Mesh& mesh) {
  check_weights_fit(weights, mesh);
  std::uint32_t vertex_count = 0;
  const std::vector<std::uint32_t> vertex = weld_points(mesh, vertex_count);
  const Graph graph = welded_graph(mesh, vertex, vertex_count);
  const Rows rows = to_rows(weights);
  const VertexRows w = welded_rows(rows, vertex, vertex_count);
  std::vector<double> dense(bone_bound(rows), 0.0);
  double energy = 0.0;
  for (std::uint32_t a = 0; a < vertex_count; ++a) {
    for (std::uint32_t i = w.offsets[a]; i < w.offsets[a + 1]; ++i) dense[w.bones[i]] = w.weights[i];
    for (std::uint32_t k = graph.offsets[a]; k < graph.offsets[a + 1]; ++k) {
      const std::uint32_t b = graph.neighbours[k];
      if (b < a) continue;  // each edge once
      double shared = 0.0;  // Σ (w_a − w_b)² = Σ_a-bones w_a² + Σ_b-bones (w_b² − 2 w_a w_b)
      for (std::uint32_t i = w.offsets[a]; i < w.offsets[a + 1]; ++i) shared += double(w.weights[i]) * w.weights[i];
      for (std::uint32_t i = w.offsets[b]; i < w.offsets[b + 1]; ++i) {
        const double wb = w.weights[i];
        shared += wb * wb - 2.0 * wb * dense[w.bones[i]];
      }
      energy += shared;
    }
    for (std::uint32_t i = w.offsets[a]; i < w.offsets[a + 1]; ++i) dense[w.bones[i]] = 0.0;
  }
  return energy;
}

std::optional<std::string> mirrored_bone_name(std::string_view name,
                                              std::span<const std::pair<std::string, std::string>> pairs) {
  for (const auto& [a, b] : pairs)
    if (a.empty() || b.empty() || a == b)
      throw Error::invalid_argument("name pair '" + a + "', '" + b + "'", "needs two different, non-empty texts");
  std::string out;
  bool sided = false;
  for (std::size_t i = 0; i < name.size();) {
    if (pairs.empty()) {
      if (const auto token = side_token(name, i)) {
        out += token->second;
        i += token->first;
        sided = true;
        continue;
      }
    } else {
      std::size_t best = 0;
      const std::string* replacement = nullptr;
      for (const auto& [a, b] : pairs) {
        if (a.size() > best && name.substr(i, a.size()) == a) best = a.size(), replacement = &b;
        if (b.size() > best && name.substr(i, b.size()) == b) best = b.size(), replacement = &a;
      }
      if (replacement) {
        out += *replacement;
        i += best;
        sided = true;
        continue;
      }
    }
    out += name[i++];
  }
  if (!sided) return std::nullopt;
  return out;
}

MirrorWeightsResult mirror_weights(const SkinWeights& weights, const Mesh& mesh, const Skeleton& skeleton,
                                   const MirrorWeightsOptions& options) {
  if (options.axis < -1 || options.axis > 2) throw Error::invalid_argument("axis", "must be -1, 0, 1 or 2");
  if (options.plane && !std::isfinite(*options.plane)) throw Error::invalid_argument("plane", "must be finite");
  if (!std::isfinite(options.tolerance) || options.tolerance == 0.0f)
    throw Error::invalid_argument("tolerance", "must be finite and > 0 (or < 0 for the default)");
  check_weights_fit(weights, mesh);
  const std::size_t bone_count = skeleton.bone_count();
  const Rows rows = to_rows(weights);
  for (std::uint16_t b : rows.bones)
    if (b >= bone_count)
      throw Error::invalid_argument("weights", "name bone " + std::to_string(b) + ", past the skeleton's " +
                                                   std::to_string(bone_count) + " bones");

  // --- bone partners: itself for a middle bone, -1 for a sided bone without one, -2 for an ambiguous one ---
  std::unordered_map<std::string, std::vector<std::int32_t>> by_name;
  for (std::size_t b = 0; b < bone_count; ++b)
    by_name[skeleton.bone(static_cast<std::int32_t>(b)).name].push_back(static_cast<std::int32_t>(b));
  std::vector<std::int32_t> partner(bone_count);
  std::vector<std::string> wanted(bone_count);
  MirrorWeightsResult result;
  glm::dvec3 spread(0.0), middle_sum(0.0);
  for (std::size_t b = 0; b < bone_count; ++b) {
    const auto name = mirrored_bone_name(skeleton.bone(static_cast<std::int32_t>(b)).name, options.name_pairs);
    if (!name) {
      partner[b] = static_cast<std::int32_t>(b);
      continue;
    }
    wanted[b] = *name;
    const auto found = by_name.find(*name);
    partner[b] = found == by_name.end() ? -1 : found->second.size() > 1 ? -2 : found->second[0];
    if (partner[b] > static_cast<std::int32_t>(b)) {
      ++result.bone_pairs;
      const glm::vec3 head_a = glm::vec3(skeleton.bind_world()[b][3]);
      const glm::vec3 head_b = glm::vec3(skeleton.bind_world()[static_cast<std::size_t>(partner[b])][3]);
      spread += glm::abs(glm::dvec3(head_a - head_b));
      middle_sum += 0.5 * (glm::dvec3(head_a) + glm::dvec3(head_b));
    }
  }
  int axis = options.axis;
  if (axis < 0) {
    if (result.bone_pairs == 0)
      throw Error::invalid_argument("skeleton", "has no left/right bone pair to find the mirror axis by: give it");
    axis = spread.x >= spread.y && spread.x >= spread.z ? 0 : spread.y >= spread.z ? 1 : 2;
  }
  const float plane = options.plane           ? *options.plane
                      : result.bone_pairs > 0 ? static_cast<float>(middle_sum[axis] / double(result.bone_pairs))
                                              : 0.0f;
  result.axis = axis;
  result.plane = plane;

  // --- the tolerance and a grid of cells of that size over the points ---
  glm::vec3 lo(INFINITY), hi(-INFINITY);
  for (std::size_t p = 0; p < mesh.positions.size(); ++p) {
    const glm::vec3 v = mesh.positions[p];
    if (!std::isfinite(v.x) || !std::isfinite(v.y) || !std::isfinite(v.z))
      throw Error::invalid_argument("point " + std::to_string(p), "is not finite");
    lo = glm::min(lo, v);
    hi = glm::max(hi, v);
  }
  float tolerance = options.tolerance;
  if (tolerance < 0.0f) {
    tolerance = mesh.positions.empty() ? 1.0f : 1e-3f * glm::length(hi - lo);
    if (!(tolerance > 0.0f) || !std::isfinite(tolerance)) tolerance = 1e-6f;
  }
  using Cell = std::array<std::int64_t, 3>;
  auto cell_of = [&](glm::vec3 v) {
    Cell c;
    for (int k = 0; k < 3; ++k)
      c[k] = static_cast<std::int64_t>(std::clamp(std::floor(double(v[k]) / tolerance), -1e15, 1e15));
    return c;
  };
  std::vector<std::pair<Cell, std::uint32_t>> grid(mesh.positions.size());
  for (std::uint32_t p = 0; p < grid.size(); ++p) grid[p] = {cell_of(mesh.positions[p]), p};
  std::sort(grid.begin(), grid.end());
  auto reflect = [&](glm::vec3 v) {
    v[axis] = 2.0f * plane - v[axis];
    return v;
  };
  // The point nearest to `target` within the tolerance (ties: lower index), or -1.
  auto nearest = [&](glm::vec3 target) {
    const Cell centre = cell_of(target);
    std::int64_t best = -1;
    float best2 = tolerance * tolerance;
    for (std::int64_t dx = -1; dx <= 1; ++dx)
      for (std::int64_t dy = -1; dy <= 1; ++dy)
        for (std::int64_t dz = -1; dz <= 1; ++dz) {
          const Cell c{centre[0] + dx, centre[1] + dy, centre[2] + dz};
          auto it = std::lower_bound(grid.begin(), grid.end(), std::make_pair(c, std::uint32_t{0}));
          for (; it != grid.end() && it->first == c; ++it) {
            const glm::vec3 d = mesh.positions[it->second] - target;
            const float d2 = glm::dot(d, d);
            if (d2 < best2 || (d2 == best2 && best >= 0 && it->second < best) || (d2 == best2 && best < 0)) {
              best2 = d2;
              best = it->second;
            }
          }
        }
    return best;
  };

  // --- each point that takes its mirror's weights ---
  SkinWeights out;
  Influences row;
  std::size_t missing = 0, first_missing = 0;
  for (std::size_t p = 0; p < rows.size(); ++p) {
    const float side = mesh.positions[p][axis] - plane;
    const bool takes = options.mode == MirrorMode::flip            ? true
                       : options.mode == MirrorMode::from_positive ? side < -tolerance
                                                                   : side > tolerance;
    row.clear();
    if (!takes) {
      for (std::size_t i = rows.begin(p); i < rows.end(p); ++i) row.emplace_back(rows.bones[i], rows.weights[i]);
      append(out, row);
      continue;
    }
    const glm::vec3 image = reflect(mesh.positions[p]);
    const std::int64_t q = nearest(image);
    if (q < 0) {
      if (missing++ == 0) first_missing = p;
      append(out, row);
      continue;
    }
    for (std::size_t i = rows.begin(static_cast<std::size_t>(q)); i < rows.end(static_cast<std::size_t>(q)); ++i) {
      const std::uint16_t b = rows.bones[i];
      if (partner[b] == -1)
        throw Error::invalid_argument(label(skeleton, b), "has no mirror partner: no bone is named '" + wanted[b] +
                                                              "' (it weights point " + std::to_string(q) + ")");
      if (partner[b] == -2)
        throw Error::invalid_argument(label(skeleton, b),
                                      "has no single mirror partner: several bones are named '" + wanted[b] + "'");
      row.emplace_back(static_cast<std::uint16_t>(partner[b]), rows.weights[i]);
    }
    ++result.points;
    append(out, row);
  }
  if (missing > 0) {
    char tol[32];
    std::snprintf(tol, sizeof tol, "%.6g", double(tolerance));
    throw Error::invalid_argument(
        "point " + std::to_string(first_missing) + " at " + format_point(mesh.positions[first_missing]),
        "has no mirror point within " + std::string(tol) + " of its reflection " +
            format_point(reflect(mesh.positions[first_missing])) + " (" + std::to_string(missing) +
            " such points in all)");
  }
  result.weights = std::move(out);
  return result;
}

}  // namespace deform
