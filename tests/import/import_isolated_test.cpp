// import_model_isolated: the same model as import_model, and a crash, hang or garbage in the importer process becomes
// a deform::Error naming the file, never a crash of the caller.
#include <doctest/doctest.h>

#include <filesystem>
#include <fstream>
#include <string>

#include <sys/stat.h>

#include "deform/import/import.hpp"
#include "deform/runtime/error.hpp"

namespace fs = std::filesystem;

namespace {

const char* const models = "/usr/share/assimp/models";

// A missing model fails the test (nothing is skipped silently): scripts/deps.sh installs assimp-testmodels.
std::string model(const char* relative) {
  const fs::path path = fs::path(models) / relative;
  REQUIRE_MESSAGE(fs::exists(path), path.string() << " is missing: install Debian's assimp-testmodels");
  return path.string();
}

// A stand-in worker: a shell script doing what a misbehaving importer does.
std::string fake_worker(const std::string& name, const std::string& body) {
  const fs::path path = fs::temp_directory_path() / ("deform_fake_worker_" + name);
  std::ofstream(path) << "#!/bin/sh\n" << body << "\n";
  fs::permissions(path, fs::perms::owner_all);
  return path.string();
}

std::string failure(const std::string& path, const deform::IsolationLimits& limits) {
  try {
    (void)deform::import_model_isolated(path, {}, limits);
  } catch (const deform::Error& e) {
    return e.what();
  }
  return "no error";
}

}  // namespace

TEST_CASE("an isolated import gives what an import in this process gives") {
  for (const char* relative : {"X/Testwuson.X", "glTF2/simple_skin/simple_skin.gltf", "FBX/huesitos.fbx"}) {
    const std::string path = model(relative);
    CAPTURE(path);
    const deform::ImportedModel here = deform::import_model(path);
    const deform::ImportedModel isolated = deform::import_model_isolated(path);
    CHECK(isolated.model.name == here.model.name);
    CHECK(isolated.model.mesh.positions == here.model.mesh.positions);
    CHECK(isolated.model.mesh.triangles == here.model.mesh.triangles);
    CHECK(isolated.model.mesh.vertex_normals == here.model.mesh.vertex_normals);
    CHECK(isolated.model.mesh.materials.size() == here.model.mesh.materials.size());
    CHECK(isolated.model.weights == here.model.weights);
    REQUIRE(isolated.model.skeleton.bone_count() == here.model.skeleton.bone_count());
    for (std::size_t b = 0; b < here.model.skeleton.bone_count(); ++b)
      CHECK(isolated.model.skeleton.bones()[b] == here.model.skeleton.bones()[b]);
    REQUIRE(isolated.clips.size() == here.clips.size());
    for (std::size_t c = 0; c < here.clips.size(); ++c) {
      CHECK(isolated.clips[c].name == here.clips[c].name);
      CHECK(isolated.clips[c].channels.size() == here.clips[c].channels.size());
    }
    CHECK(isolated.warnings == here.warnings);
    CHECK(isolated.rigged == here.rigged);
    CHECK(isolated.file_bind_world == here.file_bind_world);
    // The names of the submeshes travel beside the mesh (ImportedModel::submesh_names), one per submesh.
    REQUIRE(here.submesh_names.size() == here.model.mesh.submeshes.size());
    CHECK(isolated.submesh_names == here.submesh_names);
  }
}

TEST_CASE("a file the importer refuses is an error naming it, as in this process") {
  const fs::path bad = fs::temp_directory_path() / "deform_isolated_bad.gltf";
  std::ofstream(bad) << "{ this is not glTF";
  const std::string message = failure(bad.string(), {});
  CHECK(message.find(bad.string()) == 0);
  CHECK(message.find("crashed") == std::string::npos);
  CHECK(failure("/nonexistent/model.fbx", {}).find("/nonexistent/model.fbx") == 0);
}

TEST_CASE("a deep node chain that overflows Assimp's stack is an error, not a crash") {
  // 20,000 nested nodes with the mesh at the bottom: Assimp's glTF reader recurses once per level.
  const fs::path deep = fs::temp_directory_path() / "deform_isolated_deep.gltf";
  {
    std::ofstream out(deep);
    out << R"({"asset": {"version": "2.0"}, "scene": 0, "scenes": [{"nodes": [0]}], "nodes": [)";
    constexpr int depth = 20000;
    for (int i = 0; i < depth; ++i) out << (i ? "," : "") << R"({"children": [)" << i + 1 << "]}";
    out << R"(, {"mesh": 0}], "meshes": [{"primitives": [{"attributes": {"POSITION": 0}}]}],)"
        << R"("accessors": [{"bufferView": 0, "componentType": 5126, "count": 3, "type": "VEC3",)"
        << R"("min": [0, 0, 0], "max": [1, 1, 0]}], "bufferViews": [{"buffer": 0, "byteLength": 36}],)"
        << R"("buffers": [{"byteLength": 36, "uri": "data:application/octet-stream;base64,)"
        << R"(AAAAAAAAAAAAAAAAAACAPwAAAAAAAAAAAAAAAAAAgD8AAAAA"}]})";
  }
  deform::IsolationLimits limits;
  limits.max_stack_bytes = 1 << 20;  // 1 MiB: the recursion does not fit
  const std::string message = failure(deep.string(), limits);
  CHECK(message.find(deep.string()) == 0);
  CHECK(message != "no error");
}

TEST_CASE("a 2 KB glTF whose nodes form a DAG of 2^24 paths is refused or stopped at the memory limit") {
  // Two nodes per level, each the parent of both nodes of the next level: Assimp copies every path, 2^24 leaves.
  const fs::path dag = fs::temp_directory_path() / "deform_isolated_dag.gltf";
  {
    std::ofstream out(dag);
    out << R"({"asset": {"version": "2.0"}, "scene": 0, "scenes": [{"nodes": [0]}], "nodes": [)";
    constexpr int levels = 24;
    for (int i = 0; i < levels; ++i)
      for (int twin = 0; twin < 2; ++twin) out << R"({"children": [)" << 2 * (i + 1) << "," << 2 * (i + 1) + 1 << "]},";
    out << R"({"mesh": 0}, {"mesh": 0}], "meshes": [{"primitives": [{"attributes": {"POSITION": 0}}]}],)"
        << R"("accessors": [{"bufferView": 0, "componentType": 5126, "count": 3, "type": "VEC3",)"
        << R"("min": [0, 0, 0], "max": [1, 1, 0]}], "bufferViews": [{"buffer": 0, "byteLength": 36}],)"
        << R"("buffers": [{"byteLength": 36, "uri": "data:application/octet-stream;base64,)"
        << R"(AAAAAAAAAAAAAAAAAACAPwAAAAAAAAAAAAAAAAAAgD8AAAAA"}]})";
  }
  deform::IsolationLimits limits;
  limits.max_memory_bytes = 256ull << 20;
  const std::string message = failure(dag.string(), limits);
  CAPTURE(message);
  CHECK(message.find(dag.string()) == 0);
  // The glTF reader refuses a node with two parents; Assimp (through the same limits) runs out of memory.
  CHECK((message.find("bad_alloc") != std::string::npos || message.find("memory") != std::string::npos ||
         message.find("more than one parent") != std::string::npos));
}

TEST_CASE("a .glb whose header claims a 4 GB JSON chunk is refused without allocating it") {
  const fs::path glb = fs::temp_directory_path() / "deform_isolated_huge_chunk.glb";
  {
    std::ofstream out(glb, std::ios::binary);
    const std::uint32_t header[5] = {0x46546C67u, 2u, 0xFFFFFFF0u, 0xFFFFFFE0u, 0x4E4F534Au};  // glTF, v2, JSON
    out.write(reinterpret_cast<const char*>(header), sizeof header);
    out << R"({"asset": {"version": "2.0"}})" << std::string(600, ' ');
  }
  deform::IsolationLimits limits;
  limits.max_memory_bytes = 256ull << 20;
  const std::string message = failure(glb.string(), limits);
  CAPTURE(message);
  CHECK(message.find(glb.string()) == 0);
}

TEST_CASE("an importer that crashes, hangs, floods or answers garbage is stopped and reported") {
  const std::string path = "/some/model.glb";
  deform::IsolationLimits limits;
  limits.worker = fake_worker("crash", "kill -SEGV $$");
  CHECK(failure(path, limits).find("crashed (signal 11") != std::string::npos);
  limits.worker = fake_worker("hang", "exec sleep 30");
  limits.max_seconds = 0.5;
  CHECK(failure(path, limits).find("took more than") != std::string::npos);
  limits.max_seconds = 60.0;
  limits.worker = fake_worker("flood", "exec head -c 3000000 /dev/zero");
  limits.max_output_bytes = 1 << 20;
  CHECK(failure(path, limits).find("sent back more than") != std::string::npos);
  limits.max_output_bytes = 4ull << 30;
  limits.worker = fake_worker("garbage", "echo 'not a model'");
  CHECK(failure(path, limits).find("malformed") != std::string::npos);
  // The path is the worker's last argument.
  limits.worker = fake_worker("refuse", "for last; do :; done; echo \"$last: line 3: bad thing\" >&2; exit 2");
  CHECK(failure(path, limits) == path + ": line 3: bad thing");
  limits.worker = "/nonexistent/worker";
  CHECK_THROWS_AS(deform::import_model_isolated(path, {}, limits), deform::Error);
}
