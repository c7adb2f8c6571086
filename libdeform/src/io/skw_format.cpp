// .skw skin weight files: text, one line per OBJ `v` (docs/formats.md).
#include <algorithm>
#include <charconv>
#include <cmath>
#include <type_traits>

#include "deform/io/atomic_file.hpp"
#include "deform/runtime/error.hpp"
#include "deform/runtime/skeleton.hpp"
#include "deform/io/sk.hpp"
#include "deform/io/pose_json.hpp"
#include "float_text.hpp"
namespace deform {
namespace {

// Splits a line (comment already cut) into whitespace-separated tokens, reusing `tokens`.
void split(std::string_view line, std::vector<std::string_view>& tokens) {
  tokens.clear();
  std::size_t i = 0;
  while (i < line.size()) {
    while (i < line.size() &&
           (line[i] == ' ' || line[i] == '\t' || line[i] == '\r' || line[i] == '\v' || line[i] == '\f'))
      ++i;
    const std::size_t start = i;
    while (i < line.size() &&
           !(line[i] == ' ' || line[i] == '\t' || line[i] == '\r' || line[i] == '\v' || line[i] == '\f'))
      ++i;
    if (i > start) tokens.push_back(line.substr(start, i - start));
  }
}

template <typename T>
bool parse_number(std::string_view token, T& value) {
  const char* end = token.data() + token.size();
  if constexpr (std::is_floating_point_v<T>) {
    const auto [ptr, ec] = detail::read_decimal(token.data(), end, value);
    return ec == std::errc() && ptr == end;
  } else {
    const auto [ptr, ec] = std::from_chars(token.data(), end, value);
    return ec == std::errc() && ptr == end;
  }
}

struct Influence {
  std::uint32_t bone;
  float weight;
};

class SkwParser {
 public:
  SkwParser(const std::string& name, std::size_t point_count, std::size_t bone_count, int max_influences)
      : name_(name), point_count_(point_count), bone_count_(bone_count), max_influences_(max_influences) {}

  SkinWeights parse(std::string_view text) {
    std::vector<std::string_view> tokens;
    std::size_t start = 0;
    while (start < text.size()) {
      std::size_t end = text.find('\n', start);
      if (end == std::string_view::npos) end = text.size();
      ++line_;
      std::string_view line = text.substr(start, end - start);
      start = end + 1;
      line = line.substr(0, line.find('#'));
      split(line, tokens);
      if (!tokens.empty()) take(tokens);
    }
    if (state_ == State::header) fail("", "missing header 'skw 1'");
    if (state_ == State::count) fail("", "missing 'vertices N' line");
    if (next_vertex_ < point_count_) fail(vertex(next_vertex_), "missing (the file ends before it)");
    if (!weights_.extra_points.empty())  // the end of the last row
      weights_.extra_offsets.push_back(static_cast<std::uint32_t>(weights_.extra_bones.size()));
    return std::move(weights_);
  }

 private:
  enum class State { header, count, vertices };

  [[noreturn]] void fail(const std::string& element, const std::string& message) const {
    throw Error::at_line(name_, line_, element, message);
  }
  static std::string vertex(std::size_t index) { return "vertex " + std::to_string(index); }

  void take(const std::vector<std::string_view>& tokens) {
    if (state_ == State::header) {
      if (tokens.size() != 2 || tokens[0] != "skw") fail("", "expected the header 'skw 1'");
      if (tokens[1] != "1") fail("", "unsupported .skw version '" + std::string(tokens[1]) + "' (this reads 1)");
      state_ = State::count;
      return;
    }
    if (state_ == State::count) {
      std::uint64_t count = 0;
      if (tokens.size() != 2 || tokens[0] != "vertices" || !parse_number(tokens[1], count))
        fail("", "expected 'vertices N'");
      if (count != point_count_)
        fail("", "vertices " + std::to_string(count) + " does not match the mesh's " + std::to_string(point_count_) +
                     " points");
      // Only now, with the count known to be the mesh's own, is it safe to allocate from it.
      weights_.bones.assign(point_count_, glm::u16vec4(0));
      weights_.weights.assign(point_count_, glm::vec4(0.0f));
      listed_on_.assign(std::min<std::size_t>(bone_count_, 0x10000), 0);  // ids above 0xFFFF are refused
      state_ = State::vertices;
      return;
    }
    take_vertex(tokens);
  }

  void take_vertex(const std::vector<std::string_view>& tokens) {
    std::uint64_t index = 0;
    if (!parse_number(tokens[0], index)) fail("", "expected a vertex index, got '" + std::string(tokens[0]) + "'");
    if (next_vertex_ == point_count_)
      fail(vertex(index), "one line more than the " + std::to_string(point_count_) + " vertices declared");
    if (index < next_vertex_) fail(vertex(index), "listed again (vertices come once each, in order)");
    if (index > next_vertex_)
      fail(vertex(next_vertex_), "missing (the next line is vertex " + std::to_string(index) + ")");
    const std::string element = vertex(index);
    if (tokens.size() < 3 || tokens.size() % 2 == 0) fail(element, "expected (bone id, weight) pairs after the index");

    influences_.clear();
    double sum = 0.0;
    for (std::size_t t = 1; t < tokens.size(); t += 2) {
      std::uint64_t bone = 0;
      if (!parse_number(tokens[t], bone)) fail(element, "bad bone id '" + std::string(tokens[t]) + "'");
      if (bone >= bone_count_ || bone > 0xFFFF)
        fail(element, "bone " + std::to_string(bone) + " is out of range (the skeleton has " +
                          std::to_string(bone_count_) + " bones)");
      float weight = 0.0f;
      if (!parse_number(tokens[t + 1], weight) || !std::isfinite(weight))
        fail(element, "bad weight '" + std::string(tokens[t + 1]) + "' (a finite number >= 0)");
      if (weight < 0.0f) fail(element, "weight " + std::string(tokens[t + 1]) + " is negative");
      // A stamp per bone instead of a search of the line's pairs: a line of 65,535 pairs stays linear.
      if (listed_on_[bone] == next_vertex_ + 1) fail(element, "bone " + std::to_string(bone) + " listed twice");
      listed_on_[bone] = next_vertex_ + 1;
      influences_.push_back({static_cast<std::uint32_t>(bone), weight});
      sum += weight;
    }
    if (!(sum > 0.0)) fail(element, "no positive weight (every vertex must follow some bone)");

    // Strongest first; equal weights by bone id, so the choice does not depend on the order of the pairs.
    const auto kept = std::min<std::size_t>(influences_.size(), static_cast<std::size_t>(max_influences_));
    std::partial_sort(influences_.begin(), influences_.begin() + static_cast<std::ptrdiff_t>(kept), influences_.end(),
                      [](const Influence& a, const Influence& b) {
                        return a.weight != b.weight ? a.weight > b.weight : a.bone < b.bone;
                      });
    double kept_sum = 0.0;
    for (std::size_t k = 0; k < kept; ++k) kept_sum += influences_[k].weight;
    constexpr std::size_t slots = max_influences;
    for (std::size_t k = 0; k < kept && k < slots && influences_[k].weight > 0.0f; ++k) {
      weights_.bones[index][static_cast<int>(k)] = static_cast<std::uint16_t>(influences_[k].bone);
      weights_.weights[index][static_cast<int>(k)] = static_cast<float>(influences_[k].weight / kept_sum);
    }
    // Past the fourth (only when asked to keep more): SkinWeights' extras, one row per such vertex, in order.
    if (kept > slots && influences_[slots].weight > 0.0f) {
      weights_.extra_offsets.push_back(static_cast<std::uint32_t>(weights_.extra_bones.size()));  // the row's start
      weights_.extra_points.push_back(static_cast<std::uint32_t>(index));
      for (std::size_t k = slots; k < kept && influences_[k].weight > 0.0f; ++k) {
        weights_.extra_bones.push_back(static_cast<std::uint16_t>(influences_[k].bone));
        weights_.extra_weights.push_back(static_cast<float>(influences_[k].weight / kept_sum));
      }
    }
    ++next_vertex_;
  }

  const std::string& name_;
  std::size_t point_count_;
  std::size_t bone_count_;
  int max_influences_;
  State state_ = State::header;
  std::int64_t line_ = 0;
  std::size_t next_vertex_ = 0;
  std::vector<Influence> influences_;
  std::vector<std::size_t> listed_on_;  // per bone: 1 + the vertex whose line last listed it, 0 for none
  SkinWeights weights_;
};

}  // namespace

SkinWeights parse_skw(std::string_view text, std::size_t point_count, std::size_t bone_count, const std::string& name,
                      int influences) {
  if (influences < 1 || influences > max_requested_influences)
    throw Error::invalid_argument("influences", "must be 1 to " + std::to_string(max_requested_influences));
  return SkwParser(name, point_count, bone_count, influences).parse(text);
}

SkinWeights read_skw(const std::string& path, std::size_t point_count, std::size_t bone_count, int influences) {
  if (influences < 1 || influences > max_requested_influences)
    throw Error::invalid_argument("influences", "must be 1 to " + std::to_string(max_requested_influences));
  return parse_skw(read_file_text(path), point_count, bone_count, path, influences);
}

std::string format_skw(const SkinWeights& weights) {
  if (weights.weights.size() != weights.bones.size())
    throw Error::invalid_argument("", "bones and weights differ in size");
  const std::size_t rows = weights.extra_points.size();
  if (weights.extra_offsets.size() != (rows > 0 ? rows + 1 : 0) ||
      weights.extra_bones.size() != weights.extra_weights.size() ||
      (rows > 0 && weights.extra_offsets.back() != weights.extra_bones.size()))
    throw Error::invalid_argument("extra influences", "offsets do not match the bones and weights");
  std::string text = "skw 1\nvertices " + std::to_string(weights.size()) + "\n";
  std::size_t row = 0;  // the next point with extras
  for (std::size_t v = 0; v < weights.size(); ++v) {
    text += std::to_string(v);
    bool any = false;
    auto pair = [&](std::uint16_t bone, float w) {
      if (!std::isfinite(w) || w < 0.0f)
        throw Error::invalid_argument("vertex " + std::to_string(v), "weight is negative or not finite");
      if (w == 0.0f) return;
      any = true;
      text += ' ';
      text += std::to_string(bone);
      text += ' ';
      detail::append_shortest(text, w);
    };
    for (int k = 0; k < max_influences; ++k) pair(weights.bones[v][k], weights.weights[v][k]);
    // Influences past the fourth follow on the same line (.skw lines hold any number of pairs).
    while (row < weights.extra_points.size() && weights.extra_points[row] < v) ++row;
    if (row < weights.extra_points.size() && weights.extra_points[row] == v) {
      const std::uint32_t end = weights.extra_offsets[row + 1];
      if (weights.extra_offsets[row] > end || end > weights.extra_bones.size())
        throw Error::invalid_argument("extra influences", "offsets do not match the bones and weights");
      for (std::uint32_t e = weights.extra_offsets[row]; e < end; ++e)
        pair(weights.extra_bones[e], weights.extra_weights[e]);
    }
    if (!any) throw Error::invalid_argument("vertex " + std::to_string(v), "no positive weight");
    text += '\n';
  }
  return text;
}

void write_skw(const std::string& path, const SkinWeights& weights) { write_file_atomic(path, format_skw(weights)); }

}  // namespace deform
