// make_builtin OUT_DIR: writes the built-in character as builtin.obj, builtin.mtl, builtin.png, builtin.sk and
// builtin.skw into OUT_DIR (docs/builtin-character.md). The files in samples/data are its output; test_builtin checks
// that they still equal what deform::builtin_character() builds.
#include <cstdio>
#include <exception>
#include <stdexcept>
#include <string>
#include <vector>

#include <stb_image_write.h>

#include "deform/extras/builtin.hpp"
#include "deform/io/atomic_file.hpp"
#include "deform/io/obj.hpp"
#include "deform/io/sk.hpp"
#include "deform/runtime/model.hpp"
namespace {

constexpr int texture_size = 512;

void append_bytes(void* context, void* data, int size) {
  auto* out = static_cast<std::vector<std::uint8_t>*>(context);
  const auto* bytes = static_cast<const std::uint8_t*>(data);
  out->insert(out->end(), bytes, bytes + size);
}

}  // namespace

int main(int argc, char** argv) {
  if (argc != 2 || std::string(argv[1]) == "--help") {
    std::fprintf(argc == 2 ? stdout : stderr, "usage: make_builtin OUT_DIR   (writes builtin.{obj,mtl,png,sk,skw})\n");
    return argc == 2 ? 0 : 2;
  }
  try {
    const std::string dir = std::string(argv[1]) + "/";
    const deform::Model model = deform::builtin_character();
    std::vector<deform::ObjSubmeshNames> parts;  // one `g` per body part, all in `o builtin`
    for (const std::string_view part : deform::builtin_part_names()) parts.push_back({"builtin", std::string(part)});
    deform::ObjWriteOptions obj;
    obj.mtllib = "builtin.mtl";
    obj.submesh_names = parts;
    deform::write_obj(dir + "builtin.obj", model.mesh, model.mesh.positions, {}, obj);
    deform::write_file_atomic(dir + "builtin.mtl", deform::format_mtl(model.mesh.materials));
    deform::write_sk(dir + "builtin.sk", model.skeleton);
    deform::write_skw(dir + "builtin.skw", model.weights);

    const std::vector<std::uint8_t> pixels = deform::builtin_texture(texture_size);
    std::vector<std::uint8_t> png;
    if (!stbi_write_png_to_func(append_bytes, &png, texture_size, texture_size, 3, pixels.data(), texture_size * 3))
      throw std::runtime_error("PNG encoding failed");
    deform::write_file_atomic(dir + "builtin.png", png);
    std::printf("wrote %sbuiltin.{obj,mtl,png,sk,skw}: %zu points, %zu triangles, %zu bones\n", dir.c_str(),
                model.mesh.point_count(), model.mesh.triangle_count(), model.skeleton.bone_count());
    return 0;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "make_builtin: %s\n", e.what());
    return 1;
  }
}
