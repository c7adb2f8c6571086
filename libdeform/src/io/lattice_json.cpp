// The CLI's lattice JSON (shared/spec/cli.md, docs/formats.md): an axis-aligned Bézier lattice, its displaced control
// points and an optional vertex list.
#include <cmath>
#include <charconv>
#include <set>
#include <string>

#include <nlohmann/json.hpp>

#include "deform/io/atomic_file.hpp"
#include "deform/runtime/error.hpp"
#include "deform/runtime/lattice.hpp"
#include "deform/offline/lattice_binding.hpp"
#include "deform/io/lattice_json.hpp"
#include "runtime/finite.hpp"
namespace deform {
namespace {

using nlohmann::json;

struct Reader {
  const std::string& name;

  [[noreturn]] void fail(const std::string& key, const std::string& message) const {
    throw Error::in_file(name, "key '" + key + "'", message);
  }

  const json& array(const json& value, const std::string& key, std::size_t size) const {
    if (!value.is_array()) fail(key, "must be an array");
    if (size && value.size() != size) fail(key, "must have " + std::to_string(size) + " elements, not " +
                                                    std::to_string(value.size()));
    return value;
  }

  glm::vec3 vec3(const json& value, const std::string& key) const {
    array(value, key, 3);
    glm::vec3 v;
    for (int a = 0; a < 3; ++a) {
      const json& x = value[static_cast<std::size_t>(a)];
      const std::string element = key + "[" + std::to_string(a) + "]";
      if (!x.is_number()) fail(element, "must be a number");
      const double d = x.get<double>();
      if (!std::isfinite(d) || !std::isfinite(static_cast<float>(d))) fail(element, "is not a finite number");
      v[a] = static_cast<float>(d);
    }
    return v;
  }

  std::int64_t integer(const json& x, const std::string& key, std::int64_t min, std::int64_t max) const {
    if (!x.is_number_integer()) fail(key, "must be an integer");
    if (x.is_number_unsigned() && x.get<std::uint64_t>() > static_cast<std::uint64_t>(max))
      fail(key, std::to_string(x.get<std::uint64_t>()) + " is outside [" + std::to_string(min) + ", " +
                    std::to_string(max) + "]");
    const std::int64_t v = x.get<std::int64_t>();
    if (v < min || v > max)
      fail(key, std::to_string(v) + " is outside [" + std::to_string(min) + ", " + std::to_string(max) + "]");
    return v;
  }

  glm::ivec3 ivec3(const json& value, const std::string& key, glm::ivec3 min, glm::ivec3 max) const {
    array(value, key, 3);
    glm::ivec3 v;
    for (int a = 0; a < 3; ++a)
      v[a] = static_cast<int>(integer(value[static_cast<std::size_t>(a)], key + "[" + std::to_string(a) + "]",
                                      min[a], max[a]));
    return v;
  }
};

}  // namespace

LatticeDocument parse_lattice_json(std::string_view text, std::size_t point_count, const std::string& name) {
  json doc;
  try {
    doc = json::parse(text);
  } catch (const json::parse_error& e) {
    const std::int64_t offset = e.byte > 0 ? static_cast<std::int64_t>(e.byte) - 1 : 0;
    throw Error::at_byte(name, offset, "", std::string("malformed JSON: ") + e.what());
  } catch (const json::exception& e) {  // a number out of range
    throw Error::in_file(name, "", std::string("invalid JSON: ") + e.what());
  }
  const Reader r{name};
  if (!doc.is_object()) throw Error::in_file(name, "", "the lattice must be a JSON object");
  for (const auto& [key, value] : doc.items())
    if (key != "origin" && key != "size" && key != "degree" && key != "displacements" && key != "vertices")
      r.fail(key, "unknown key (expected origin, size, degree, displacements, vertices)");
  if (!doc.contains("origin")) r.fail("origin", "is missing");
  if (!doc.contains("size")) r.fail("size", "is missing");
  const glm::vec3 origin = r.vec3(doc["origin"], "origin");
  const glm::vec3 size = r.vec3(doc["size"], "size");
  for (int a = 0; a < 3; ++a)
    if (!(size[a] > 0.0f)) r.fail("size[" + std::to_string(a) + "]", "must be positive");
  glm::ivec3 degree(3);
  if (doc.contains("degree"))
    degree = r.ivec3(doc["degree"], "degree", glm::ivec3(1), glm::ivec3(max_bezier_degree));

  LatticeDocument out;
  out.lattice = BezierLattice(LatticeFrame::axis_aligned(origin, size), degree, name);
  if (doc.contains("displacements")) {
    const json& list = r.array(doc["displacements"], "displacements", 0);
    std::set<std::size_t> moved;
    for (std::size_t d = 0; d < list.size(); ++d) {
      const std::string key = "displacements[" + std::to_string(d) + "]";
      const json& item = list[d];
      if (!item.is_object()) r.fail(key, "must be an object {\"index\": [i, j, k], \"offset\": [dx, dy, dz]}");
      for (const auto& [k, v] : item.items())
        if (k != "index" && k != "offset") r.fail(key + "." + k, "unknown key (expected index, offset)");
      if (!item.contains("index")) r.fail(key + ".index", "is missing");
      if (!item.contains("offset")) r.fail(key + ".offset", "is missing");
      const glm::ivec3 index = r.ivec3(item["index"], key + ".index", glm::ivec3(0), degree);
      const glm::vec3 offset = r.vec3(item["offset"], key + ".offset");
      const std::size_t flat = out.lattice.index(index.x, index.y, index.z);
      if (!moved.insert(flat).second) r.fail(key + ".index", "control point listed twice");
      glm::vec3& p = out.lattice.control_points()[flat];
      p += offset;
      if (!finite(p))
        r.fail(key + ".offset", "moves the control point out of the finite range");
    }
    out.displacement_count = list.size();
  }
  if (doc.contains("vertices")) {
    const json& list = r.array(doc["vertices"], "vertices", 0);
    if (list.size() > point_count)
      r.fail("vertices", std::to_string(list.size()) + " entries for " + std::to_string(point_count) + " vertices");
    std::vector<bool> seen(point_count, false);
    out.has_vertices = true;
    for (std::size_t i = 0; i < list.size(); ++i) {
      const std::string key = "vertices[" + std::to_string(i) + "]";
      if (point_count == 0) r.fail(key, "the mesh has no vertices");
      const auto v = static_cast<std::size_t>(r.integer(list[i], key, 0, static_cast<std::int64_t>(point_count) - 1));
      if (seen[v]) r.fail(key, "vertex " + std::to_string(v) + " is listed twice");
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
        throw Error::at_line(name, line, element,
                             "vertex " + std::to_string(value) + " is out of range (" + std::to_string(point_count) +
                                 " vertices)");
      if (seen[value]) throw Error::at_line(name, line, element, "vertex " + std::to_string(value) + " is listed twice");
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
