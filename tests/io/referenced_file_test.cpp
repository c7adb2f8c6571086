// The confinement rule for files a model names (deform/io/referenced_file.hpp) and the readers that apply it.
#include <doctest/doctest.h>

#include <filesystem>
#include <fstream>
#include <string>
#include <string_view>

#include <nlohmann/json.hpp>
#include <unistd.h>

#include "deform/io/atomic_file.hpp"
#include "deform/io/gltf_export.hpp"
#include "deform/io/model_files.hpp"
#include "deform/io/obj.hpp"
#include "deform/io/referenced_file.hpp"
#include "deform/runtime/error.hpp"

namespace fs = std::filesystem;
using deform::ReferencePolicy;
using deform::ReferenceSyntax;
using deform::resolve_referenced_file;

namespace {

// root/model/m.obj beside root/secret.txt (outside the model's folder) and root/model/inside.mtl.
struct Tree {
  fs::path root = fs::temp_directory_path() / ("deform_referenced_" + std::to_string(::getpid()));
  fs::path model = root / "model";
  std::string referrer = (model / "m.obj").string();
  Tree() {
    fs::remove_all(root);
    fs::create_directories(model / "sub");
    write(root / "secret.txt", "SECRET-5f3a\n");
    write(model / "inside.mtl", "newmtl a\nKd 1 0 0\n");
    write(model / "sub" / "tex.png", "\x89PNG\r\n\x1a\n0123456789");
  }
  ~Tree() {
    std::error_code ignored;
    fs::remove_all(root, ignored);
  }
  static void write(const fs::path& path, const std::string& text) { std::ofstream(path, std::ios::binary) << text; }
  std::string canonical(const fs::path& path) const { return fs::weakly_canonical(path).string(); }
};

// The refusal's message, which must name the referrer and key and nothing of the refused file.
std::string refusal(const std::string& referrer, const std::string& reference, const std::string& key,
                    const ReferencePolicy& policy = {}, ReferenceSyntax syntax = ReferenceSyntax::path) {
  try {
    resolve_referenced_file(referrer, reference, key, policy, syntax);
  } catch (const deform::Error& e) {
    CHECK(e.kind() == deform::Error::Kind::input);
    return e.what();
  }
  return {};
}

}  // namespace

TEST_CASE("referenced files: inside the model's folder they resolve to canonical paths") {
  const Tree tree;
  CHECK(resolve_referenced_file(tree.referrer, "inside.mtl", "mtllib") == tree.canonical(tree.model / "inside.mtl"));
  CHECK(resolve_referenced_file(tree.referrer, "sub/../inside.mtl", "mtllib") ==
        tree.canonical(tree.model / "inside.mtl"));
  CHECK(resolve_referenced_file(tree.referrer, "sub%2ftex.png", "images[0].uri", {}, ReferenceSyntax::uri) ==
        tree.canonical(tree.model / "sub" / "tex.png"));
  // An absolute path inside the folder is inside.
  CHECK(resolve_referenced_file(tree.referrer, (tree.model / "inside.mtl").string(), "mtllib") ==
        tree.canonical(tree.model / "inside.mtl"));
  // A name inside that does not exist is returned (the reader decides: warning or error), not refused.
  CHECK(resolve_referenced_file(tree.referrer, "missing.mtl", "mtllib") == tree.canonical(tree.model / "missing.mtl"));
}

TEST_CASE("referenced files: '..', absolute paths and percent-encoding out of the folder are refused") {
  const Tree tree;
  for (const std::string& reference :
       {std::string("../secret.txt"), std::string("sub/../../secret.txt"), (tree.root / "secret.txt").string(),
        std::string("/etc/passwd"), std::string("../missing-outside.txt")}) {
    CAPTURE(reference);
    const std::string message = refusal(tree.referrer, reference, "mtllib");
    CHECK(message.find(tree.referrer) != std::string::npos);
    CHECK(message.find("mtllib") != std::string::npos);
    CHECK(message.find("outside") != std::string::npos);
    CHECK(message.find("SECRET") == std::string::npos);
    CHECK(message.find(" 12 ") == std::string::npos);  // the secret's size is never given
  }
  // Percent-encoded dots and slashes are decoded before the test (glTF URIs), and only there.
  CHECK(refusal(tree.referrer, "%2e%2e%2fsecret.txt", "buffers[0].uri", {}, ReferenceSyntax::uri)
            .find("buffers[0].uri") != std::string::npos);
  CHECK(refusal(tree.referrer, "..%2Fsecret.txt", "buffers[0].uri", {}, ReferenceSyntax::uri) != "");
  CHECK(refusal(tree.referrer, "%2e%2e%2fsecret.txt", "mtllib") == "");  // a plain path: a file of that odd name
  // Nothing at all, or a NUL byte (which the system would cut the name at), is refused.
  CHECK(refusal(tree.referrer, "", "mtllib") != "");
  CHECK(refusal(tree.referrer, "inside.mtl%00/../../secret.txt", "images[0].uri", {}, ReferenceSyntax::uri) != "");
}

#ifndef _WIN32  // symbolic links on Windows need a privilege the tests do not have (and mingw's library makes none)
TEST_CASE("referenced files: symbolic links are followed before the test") {
  const Tree tree;
  fs::create_symlink(tree.root / "secret.txt", tree.model / "link.txt");
  fs::create_directory_symlink(tree.root, tree.model / "up");
  CHECK(refusal(tree.referrer, "link.txt", "map_Kd").find("map_Kd") != std::string::npos);
  CHECK(refusal(tree.referrer, "up/secret.txt", "map_Kd") != "");
  // A model whose own folder is reached through a link: its files are inside the folder the link leads to.
  fs::create_directory_symlink(tree.model, tree.root / "linked_model");
  const std::string through_link = (tree.root / "linked_model" / "m.obj").string();
  CHECK(resolve_referenced_file(through_link, "inside.mtl", "mtllib") == tree.canonical(tree.model / "inside.mtl"));
  CHECK(refusal(through_link, "../secret.txt", "mtllib") != "");
  // A link inside pointing to a file inside is fine.
  fs::create_symlink(tree.model / "inside.mtl", tree.model / "alias.mtl");
  CHECK(resolve_referenced_file(tree.referrer, "alias.mtl", "mtllib") == tree.canonical(tree.model / "inside.mtl"));
}
#endif

TEST_CASE("referenced files: allow_outside widens the rule on purpose, and only by the folders it names") {
  const Tree tree;
  ReferencePolicy policy;
  policy.allow_outside = {tree.root.string()};
  CHECK(resolve_referenced_file(tree.referrer, "../secret.txt", "mtllib", policy) ==
        tree.canonical(tree.root / "secret.txt"));
  policy.allow_outside = {(tree.root / "elsewhere").string()};
  CHECK(refusal(tree.referrer, "../secret.txt", "mtllib", policy) != "");
  CHECK(deform::lies_inside((tree.model / "inside.mtl").string(), tree.model.string()));
  CHECK_FALSE(deform::lies_inside((tree.root / "secret.txt").string(), tree.model.string()));
  CHECK_FALSE(deform::lies_inside(tree.model.string(), tree.model.string()));  // the folder itself is not inside it
}

TEST_CASE("referenced files: the OBJ reader confines mtllib and map_Kd, and never quotes a refused file") {
  const Tree tree;
  Tree::write(tree.root / "secret.mtl", "SECRET-line one\nnewmtl s\nmap_Kd x.png\n");
  for (const std::string& mtllib : {std::string("../secret.mtl"), (tree.root / "secret.mtl").string()}) {
    CAPTURE(mtllib);
    Tree::write(tree.model / "m.obj", "mtllib " + mtllib + "\nv 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n");
    deform::Warnings warnings;
    try {
      deform::read_obj(tree.referrer, &warnings);
      FAIL("an MTL file outside the model's folder was read");
    } catch (const deform::Error& e) {
      const std::string message = e.what();
      CHECK(message.find("line 1") != std::string::npos);
      CHECK(message.find("mtllib") != std::string::npos);
      CHECK(message.find("SECRET") == std::string::npos);
    }
    for (const std::string& w : warnings.messages) CHECK(w.find("SECRET") == std::string::npos);
    // Allowed on purpose, it is read.
    ReferencePolicy policy;
    policy.allow_outside = {tree.root.string()};
    CHECK(deform::read_obj(tree.referrer, &warnings, policy).materials.size() == 1);
  }
  // map_Kd in an MTL inside naming a file outside.
  Tree::write(tree.model / "inside.mtl", "newmtl a\nmap_Kd ../secret.txt\n");
  Tree::write(tree.model / "m.obj", "mtllib inside.mtl\nv 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n");
  CHECK_THROWS_WITH_AS(deform::read_obj(tree.referrer), doctest::Contains("map_Kd"), deform::Error);
  // A texture inside that is missing stays a warning.
  Tree::write(tree.model / "inside.mtl", "newmtl a\nmap_Kd missing.png\n");
  deform::Warnings warnings;
  CHECK(deform::read_obj(tree.referrer, &warnings).materials.size() == 1);
  CHECK(warnings.messages.size() == 1);
}

TEST_CASE("referenced files: warnings print names from files on one line") {
  const Tree tree;
  Tree::write(tree.model / "m.obj",
              "mtllib a\x01"
              "b.mtl\nv 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n");
  deform::Warnings warnings;
  deform::read_obj(tree.referrer, &warnings);
  REQUIRE(warnings.messages.size() == 1);
  CHECK(warnings.messages[0].find('\x01') == std::string::npos);
  CHECK(warnings.messages[0].find("\\x01") != std::string::npos);
  CHECK(deform::escape_control_characters("a\nb\x7f") == "a\\x0ab\\x7f");
}

TEST_CASE("referenced files: image signatures are read from the first bytes") {
  const Tree tree;
  CHECK(deform::image_format((tree.model / "sub" / "tex.png").string()) == "png");
  CHECK(deform::image_format((tree.root / "secret.txt").string()).empty());
  CHECK(deform::image_format((tree.root / "absent.png").string()).empty());
  CHECK(deform::image_format(tree.root.string()).empty());  // a folder
  Tree::write(tree.model / "t.tga", std::string(18, '\0'));
  CHECK(deform::image_format((tree.model / "t.tga").string()) == "tga");
  Tree::write(tree.model / "mm.tif", std::string("MM\0*", 4) + "rest");
  CHECK(deform::image_format((tree.model / "mm.tif").string()) == "tiff");
  Tree::write(tree.model / "mx.bin", "MMXX not a tiff");
  CHECK(deform::image_format((tree.model / "mx.bin").string()).empty());
}

namespace {

// A path's or a literal's UTF-8 bytes as the API takes them.
std::string utf8(const fs::path& path) {
  const std::u8string text = path.u8string();
  return std::string(text.begin(), text.end());
}
std::string str(std::u8string_view text) { return std::string(text.begin(), text.end()); }

}  // namespace

// Every path in the API is UTF-8. On Windows a name outside ASCII must reach the system as the wide name it spells,
// not as bytes in the ANSI code page: this holds the readers, the confinement, the model's name and the writers to
// that (it runs under wine in the Windows pass; on POSIX the bytes are the name).
TEST_CASE("referenced files: UTF-8 names outside ASCII, read, confined, named and written") {
  const Tree tree;
  const fs::path folder = tree.root / u8"Ωmega ünïcode 日本";
  fs::create_directories(folder);
  const std::string png("\x89PNG\r\n\x1a\n0123456789", 18);
  Tree::write(folder / u8"tëxture_日本.png", png);
  Tree::write(tree.root / u8"dehors_Ω.png", png);
  Tree::write(folder / u8"mätériaux_Ω.mtl", str(u8"newmtl peau\nKd 1 0 0\nmap_Kd tëxture_日本.png\n"));
  const std::string triangle = "v 0 0 0\nv 1 0 0\nv 0 1 0\nvt 0 0\nvt 1 0\nvt 0 1\nusemtl peau\nf 1/1 2/2 3/3\n";
  Tree::write(folder / u8"mödel_日本.obj", str(u8"mtllib mätériaux_Ω.mtl\n") + triangle);
  fs::copy_file(DEFORM_TEST_DATA "/skeleton/arm.sk", folder / u8"ßkeleton.sk");
  Tree::write(folder / u8"pöids.skw", "skw 1\nvertices 3\n0 0 1\n1 1 1\n2 1 1\n");
  const std::string obj = utf8(folder / u8"mödel_日本.obj");
  const std::string texture = str((folder / u8"tëxture_日本.png").lexically_normal().generic_u8string());

  // Read: the OBJ, its MTL and the texture it names, found inside the folder (no "not found" warning).
  deform::Warnings warnings;
  deform::ObjNames names;
  const deform::Model model = deform::load_model(obj, utf8(folder / u8"ßkeleton.sk"), utf8(folder / u8"pöids.skw"),
                                                 &warnings, deform::max_influences, {}, &names);
  for (const std::string& w : warnings.messages) FAIL_CHECK(w);
  CHECK(model.name == str(u8"mödel_日本"));
  REQUIRE(model.mesh.materials.size() == 1);
  CHECK(model.mesh.materials[0].diffuse_map == texture);
  REQUIRE(names.material_libraries.size() == 1);
  CHECK(names.material_libraries[0] == str((folder / u8"mätériaux_Ω.mtl").lexically_normal().generic_u8string()));

  // Confined: the texture inside resolves to its canonical UTF-8 path; one outside is refused, or allowed on purpose.
  CHECK(resolve_referenced_file(obj, str(u8"tëxture_日本.png"), "map_Kd") ==
        utf8(fs::weakly_canonical(folder / u8"tëxture_日本.png")));
  CHECK(refusal(obj, str(u8"../dehors_Ω.png"), "map_Kd").find("outside") != std::string::npos);
  CHECK(deform::lies_inside(texture, utf8(folder)));
  CHECK(deform::image_format(texture) == "png");
  Tree::write(folder / u8"ailleurs_Ω.mtl", str(u8"newmtl b\nmap_Kd ../dehors_Ω.png\n"));
  Tree::write(folder / u8"fuite_日本.obj", str(u8"mtllib ailleurs_Ω.mtl\n") + triangle);
  CHECK_THROWS_WITH_AS(deform::read_obj(utf8(folder / u8"fuite_日本.obj")), doctest::Contains("map_Kd"), deform::Error);
  ReferencePolicy policy;
  policy.allow_outside = {utf8(tree.root)};
  CHECK(deform::read_obj(utf8(folder / u8"fuite_日本.obj"), nullptr, policy).materials[0].diffuse_map ==
        str((tree.root / u8"dehors_Ω.png").lexically_normal().generic_u8string()));

  // Written: an OBJ naming the MTL relative to it, read back with its texture.
  const std::string obj_out = utf8(folder / u8"sortie_Ω.obj");
  deform::ObjWriteOptions obj_options;
  obj_options.mtllib = deform::material_libraries_for(names, obj_out);
  CHECK(obj_options.mtllib == str(u8"mätériaux_Ω.mtl"));
  deform::write_obj(obj_out, model.mesh, model.mesh.positions, {}, obj_options);
  const deform::Mesh back = deform::read_obj(obj_out);
  CHECK(back.point_count() == 3);
  REQUIRE(back.materials.size() == 1);
  CHECK(back.materials[0].diffuse_map == texture);

  // Written: a .gltf beside its .bin (the .bin's name made ASCII, a '_' a byte), the texture embedded from the folder.
  deform::GltfExportOptions gltf_options;
  gltf_options.texture_root = utf8(folder);
  const std::string gltf_out = utf8(folder / u8"exporté_日本.gltf");
  const deform::GltfWritten written = deform::write_gltf(gltf_out, model, gltf_options);
  CHECK(written.warnings.empty());
  CHECK(written.textures == 1);
  CHECK(written.bin == utf8(folder / "export_________.bin"));
  const nlohmann::json document = nlohmann::json::parse(deform::read_file_text(gltf_out));
  CHECK(document["buffers"][0]["uri"] == "export_________.bin");
  CHECK(document["buffers"][0]["byteLength"] == deform::read_file_bytes(written.bin).size());
  CHECK(document["images"].size() == 1);
}

// A name that is not UTF-8 names no file on Windows (no wide name corresponds to it): a reader refuses it naming the
// file, line and statement, and the checks that answer yes or no answer no. On POSIX the bytes are the name.
TEST_CASE("referenced files: names that are not UTF-8") {
  const Tree tree;
  const std::string invalid = "\xff\xfe.png";
  Tree::write(tree.model / "bad.mtl", "newmtl a\nmap_Kd " + invalid + "\n");
  Tree::write(tree.model / "m.obj", "mtllib bad.mtl\nv 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n");
  Tree::write(tree.model / "n.obj", "mtllib \xff.mtl\nv 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n");
  const std::string texture = utf8(tree.model) + "/" + invalid;
  deform::Warnings warnings;
#ifdef _WIN32
  CHECK_THROWS_WITH_AS(deform::read_obj(tree.referrer, &warnings), doctest::Contains("map_Kd"), deform::Error);
  CHECK_THROWS_WITH_AS(deform::read_obj(utf8(tree.model / "n.obj"), &warnings), doctest::Contains("not UTF-8"),
                       deform::Error);
  CHECK(refusal(tree.referrer, invalid, "map_Kd").find("not UTF-8") != std::string::npos);
  CHECK_THROWS_WITH_AS(deform::write_file_atomic(texture, std::string_view("x")), doctest::Contains("not UTF-8"),
                       deform::Error);
  CHECK_FALSE(deform::lies_inside(texture, utf8(tree.model)));
#else
  CHECK(deform::read_obj(tree.referrer, &warnings).materials.size() == 1);
  CHECK(deform::read_obj(utf8(tree.model / "n.obj"), &warnings).materials.empty());
  CHECK(resolve_referenced_file(tree.referrer, invalid, "map_Kd") == utf8(tree.model) + "/" + invalid);
  CHECK(deform::lies_inside(texture, utf8(tree.model)));
#endif
  CHECK(deform::image_format(texture).empty());
  // glTF export leaves such a texture out with a warning naming why (on POSIX: a file that does not exist).
  Tree::write(tree.model / "t.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nvt 0 0\nvt 1 0\nvt 0 1\nf 1/1 2/2 3/3\n");
  fs::copy_file(DEFORM_TEST_DATA "/skeleton/arm.sk", tree.model / "t.sk");
  Tree::write(tree.model / "t.skw", "skw 1\nvertices 3\n0 0 1\n1 1 1\n2 1 1\n");
  deform::Model model =
      deform::load_model(utf8(tree.model / "t.obj"), utf8(tree.model / "t.sk"), utf8(tree.model / "t.skw"));
  model.mesh.materials.assign(1, deform::Material{});
  model.mesh.materials[0].diffuse_map = texture;
  deform::GltfExportOptions options;
  options.texture_root = utf8(tree.model);
  const deform::GltfWritten written = deform::write_gltf(utf8(tree.model / "t.glb"), model, options);
  REQUIRE(written.warnings.size() == 1);
#ifdef _WIN32
  CHECK(written.warnings[0].find("not UTF-8") != std::string::npos);
#else
  CHECK(written.warnings[0].find("not found") != std::string::npos);
#endif
}
