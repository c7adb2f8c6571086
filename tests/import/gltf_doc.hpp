#pragma once
// Test support: glTF 2.0 documents written by hand, one buffer (embedded as a base64 data URI) and one buffer view
// per accessor, for the tests that feed the glTF reader files of their own (tests/import/gltf_import_test.cpp,
// tests/character/morph_test.cpp).
#include <cstdint>
#include <cstring>
#include <string>
#include <vector>

namespace gltf_doc {

inline std::string base64(const std::vector<std::uint8_t>& bytes) {
  static const char* digits = "ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
  std::string out;
  for (std::size_t i = 0; i < bytes.size(); i += 3) {
    const std::uint32_t n = (std::uint32_t{bytes[i]} << 16) | (i + 1 < bytes.size() ? bytes[i + 1] << 8 : 0) |
                            (i + 2 < bytes.size() ? bytes[i + 2] : 0);
    out += digits[(n >> 18) & 63];
    out += digits[(n >> 12) & 63];
    out += i + 1 < bytes.size() ? digits[(n >> 6) & 63] : '=';
    out += i + 2 < bytes.size() ? digits[n & 63] : '=';
  }
  return out;
}

// A glTF document under construction: one buffer, accessors appended as JSON text.
struct Doc {
  std::vector<std::uint8_t> data;
  std::vector<std::string> views, accessors;

  template <class T>
  int accessor(const std::vector<T>& values, const char* type, int component, const std::string& extra = "") {
    while (data.size() % 4) data.push_back(0);
    const std::size_t offset = data.size();
    data.resize(offset + values.size() * sizeof(T));
    std::memcpy(data.data() + offset, values.data(), values.size() * sizeof(T));
    views.push_back(R"({"buffer": 0, "byteOffset": )" + std::to_string(offset) + R"(, "byteLength": )" +
                    std::to_string(values.size() * sizeof(T)) + "}");
    const std::size_t width = std::string(type) == "SCALAR" ? 1 : std::string(type) == "MAT4" ? 16 : type[3] - '0';
    accessors.push_back(R"({"bufferView": )" + std::to_string(views.size() - 1) + R"(, "componentType": )" +
                        std::to_string(component) + R"(, "count": )" + std::to_string(values.size() / width) +
                        R"(, "type": ")" + type + "\"" + extra + "}");
    return static_cast<int>(accessors.size() - 1);
  }

  // The document with `body` (nodes, meshes, skins, animations, ...) and this buffer.
  std::string json(const std::string& body) const {
    std::string out = R"({"asset": {"version": "2.0"}, )" + body + R"(, "bufferViews": [)";
    for (std::size_t i = 0; i < views.size(); ++i) out += (i ? ", " : "") + views[i];
    out += R"(], "accessors": [)";
    for (std::size_t i = 0; i < accessors.size(); ++i) out += (i ? ", " : "") + accessors[i];
    out += R"(], "buffers": [{"byteLength": )" + std::to_string(data.size()) +
           R"(, "uri": "data:application/octet-stream;base64,)" + base64(data) + R"("}]})";
    return out;
  }
};

}  // namespace gltf_doc
