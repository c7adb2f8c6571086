// The CLI's lattice JSON (docs/cli.md, docs/formats.md): an axis-aligned Bézier lattice, its displaced control
// points and an optional vertex list.
#include <charconv>
#include <set>
#include <string>

#include <nlohmann/json.hpp>

#include "deform/io/atomic_file.hpp"
#include "deform/runtime/error.hpp"
#include "deform/runtime/lattice.hpp"
#include "deform/offline/lattice_binding.hpp"
#include "deform/io/lattice_json.hpp"
#include "json_reader.hpp"
#include "finite.hpp"
namespace deform {

LatticeDocument parse_lattice_json(std::string_view text, std::size_t point_count, const std::string& name) {
  const nlohmann::json document = detail::parse_json(text, name);
  const detail::JsonReader root(name, document);
  if (!root.is_object()) root.fail("the lattice must be a JSON object");
  root.expect_object({"origin", "size", "degree", "displacements", "vertices"});
  const glm::vec3 origin = root.at("origin").vec3();
  const detail::JsonReader size_key = root.at("size");
  const glm::vec3 size = size_key.vec3();
  for (std::size_t a = 0; a < 3; ++a)
    if (!(size[static_cast<glm::length_t>(a)] > 0.0f)) size_key.at(a).fail("must be positive");
  glm::ivec3 degree(3);
  if (root.has("degree")) degree = root.at("degree").ivec3(glm::ivec3(1), glm::ivec3(max_bezier_degree));

  LatticeDocument out;
  out.lattice = BezierLattice(LatticeFrame::axis_aligned(origin, size), degree, name);
  if (root.has("displacements")) {
    const detail::JsonReader list = root.at("displacements");
    const std::size_t count = list.array_size();
    std::set<std::size_t> moved;
    for (std::size_t d = 0; d < count; ++d) {
      const detail::JsonReader item = list.at(d);
      if (!item.is_object()) item.fail("must be an object {\"index\": [i, j, k], \"offset\": [dx, dy, dz]}");
      item.expect_object({"index", "offset"});
      const detail::JsonReader index_key = item.at("index");
      const detail::JsonReader offset_key = item.at("offset");
      const glm::ivec3 index = index_key.ivec3(glm::ivec3(0), degree);
      const glm::vec3 offset = offset_key.vec3();
      const std::size_t flat = out.lattice.index(index.x, index.y, index.z);
      if (!moved.insert(flat).second) index_key.fail("control point listed twice");
      glm::vec3& p = out.lattice.control_points()[flat];
      p += offset;
      if (!finite(p)) offset_key.fail("moves the control point out of the finite range");
    }
    out.displacement_count = count;
  }
  if (root.has("vertices")) {
    const detail::JsonReader list = root.at("vertices");
    const std::size_t count = list.array_size();
    if (count > point_count)
      list.fail(std::to_string(count) + " entries for " + std::to_string(point_count) + " vertices");
    std::vector<bool> seen(point_count, false);
    out.has_vertices = true;
    for (std::size_t i = 0; i < count; ++i) {
      const detail::JsonReader entry = list.at(i);
      if (point_count == 0) entry.fail("the mesh has no vertices");
      const auto v = static_cast<std::size_t>(entry.integer(0, static_cast<std::int64_t>(point_count) - 1));
      if (seen[v]) entry.fail("vertex " + std::to_string(v) + " is listed twice");
      seen[v] = true;
      out.vertices.push_back(static_cast<std::uint32_t>(v));
    }
  }
  return out;
}

LatticeDocument read_lattice_json(const std::string& path, std::size_t point_count) {
  return parse_lattice_json(read_file_text(path), point_count, path);
}

std::vector<std::uint32_t> parse_vertex_list(std::string_view text, std::size_t point_count, const std::string& name) {
  std::vector<std::uint32_t> out;
  std::vector<bool> seen(point_count, false);
  std::int64_t line = 1;
  std::size_t i = 0;
  while (i < text.size()) {
    const char c = text[i];
    if (c == '\n') {
      ++line, ++i;
    } else if (c == ' ' || c == '\t' || c == '\r') {
      ++i;
    } else if (c == '#') {
      while (i < text.size() && text[i] != '\n') ++i;
    } else {
      std::size_t end = i;
      while (end < text.size() && text[end] != ' ' && text[end] != '\t' && text[end] != '\r' && text[end] != '\n' &&
             text[end] != '#')
        ++end;
      const std::string_view token = text.substr(i, end - i);
      const std::string element = "entry " + std::to_string(out.size());
      std::uint64_t value = 0;
      const auto [ptr, ec] = std::from_chars(token.data(), token.data() + token.size(), value);
      if (ec != std::errc() || ptr != token.data() + token.size())
        throw Error::at_line(name, line, element, "'" + std::string(token) + "' is not a vertex index (0-based)");
      if (value >= point_count)
        throw Error::at_line(
            name, line, element,
            "vertex " + std::to_string(value) + " is out of range (" + std::to_string(point_count) + " vertices)");
      if (seen[value])
        throw Error::at_line(name, line, element, "vertex " + std::to_string(value) + " is listed twice");
      seen[value] = true;
      out.push_back(static_cast<std::uint32_t>(value));
      i = end;
    }
  }
  return out;
}

std::vector<std::uint32_t> read_vertex_list(const std::string& path, std::size_t point_count) {
  return parse_vertex_list(read_file_text(path), point_count, path);
}

}  // namespace deform
