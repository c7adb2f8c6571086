// Skinning decomposition (deform/offline/skinning_decomposition.hpp) and glTF out (deform/io/gltf_export.hpp): a
// Character's motion recorded frame by frame, fitted with extra bones, written as a glTF skin and clip.
#include <optional>
#include <string>
#include <vector>

#include "common.hpp"
#include "deform/character/character.hpp"
#include "deform/io/gltf_export.hpp"
#include "deform/offline/skinning_decomposition.hpp"
#include "deform/version.hpp"

namespace deform_python {

namespace {

template <class T>
py::array_t<T> array_of(const std::vector<T>& values) {
  py::array_t<T> out(static_cast<py::ssize_t>(values.size()));
  std::copy(values.begin(), values.end(), out.mutable_data());
  return out;
}

}  // namespace

void bind_decomposition(py::module_& m) {
  py::class_<deform::DecompositionFrames>(m, "DecompositionFrames",
                                          "A Character's motion, frame by frame, for decompose_skinning: each "
                                          "frame's bone matrices (after IK and spring chains) and deformed points.")
      .def(py::init([](const std::string& name) {
             deform::DecompositionFrames frames;
             frames.name = name;
             return frames;
           }),
           py::arg("name") = "bake")
      .def_readwrite("name", &deform::DecompositionFrames::name, "the clip's name in the result")
      .def(
          "add",
          [](deform::DecompositionFrames& frames, float time, const deform::Character& character) {
            const std::span<const glm::mat4> palette = character.palette(), bind = character.skeleton().bind_world();
            std::vector<glm::mat4> world(palette.size());
            for (std::size_t b = 0; b < palette.size(); ++b) world[b] = palette[b] * bind[b];
            frames.times.push_back(time);
            frames.bone_world.push_back(std::move(world));
            frames.positions.emplace_back(character.positions().begin(), character.positions().end());
          },
          py::arg("time"), py::arg("character"),
          "Records the character as its last update() left it, at `time` seconds (strictly after the last frame's).")
      .def("__len__", [](const deform::DecompositionFrames& frames) { return frames.times.size(); });

  py::class_<deform::SkinningDecomposition>(m, "SkinningDecomposition",
                                            "decompose_skinning's result: the skeleton with the extra bones, the "
                                            "weights, the clip and how close they come to the frames.")
      .def_property_readonly("skeleton",
                             [](py::object self) {
                               return py::cast(&self.cast<deform::SkinningDecomposition&>().skeleton,
                                               py::return_value_policy::reference_internal, self);
                             })
      .def_readonly("clips", &deform::SkinningDecomposition::clips, "one Animation per clip given, in order")
      .def_readonly("extra_bones", &deform::SkinningDecomposition::extra_bones)
      .def_readonly("iterations", &deform::SkinningDecomposition::iterations)
      .def_readonly("rms_error", &deform::SkinningDecomposition::rms_error,
                    "root mean square distance from the frames, a fraction of the bind mesh's bounding-box diagonal")
      .def_readonly("max_error", &deform::SkinningDecomposition::max_error, "the largest distance, likewise")
      .def_property_readonly("moved_points",
                             [](const deform::SkinningDecomposition& d) { return array_of(d.moved_points); })
      .def_property_readonly("frame_rms_error",
                             [](const deform::SkinningDecomposition& d) { return array_of(d.frame_rms_error); })
      .def_property_readonly("frame_max_error",
                             [](const deform::SkinningDecomposition& d) { return array_of(d.frame_max_error); })
      .def(
          "model",
          [](const deform::SkinningDecomposition& d, const deform::Model& rest) {
            auto out = std::make_shared<deform::Model>(rest);
            out->skeleton = d.skeleton;
            out->weights = d.weights;
            return out;
          },
          py::arg("rest"),
          "A copy of `rest` (the model the frames were recorded from) with this skeleton and weights.");

  m.def(
      "decompose_skinning",
      [](const deform::Model& model, const py::object& frames, std::size_t max_bones, int influences, int iterations,
         float moved_tolerance, const std::optional<FloatArray>& seeds, unsigned threads) {
        // One clip's frames, or a list of clips decomposed together (one set of bones and weights).
        std::vector<deform::DecompositionFrames> clips;
        if (py::isinstance<deform::DecompositionFrames>(frames))
          clips.push_back(frames.cast<deform::DecompositionFrames>());
        else clips = frames.cast<std::vector<deform::DecompositionFrames>>();
        deform::DecompositionOptions options;
        options.max_bones = max_bones;
        options.influences = influences;
        options.iterations = iterations;
        options.moved_tolerance = moved_tolerance;
        options.threads = threads;
        if (seeds) {
          const std::span<const glm::vec3> s = as_vec3(*seeds, "seeds");
          options.seeds.assign(s.begin(), s.end());
        }
        py::gil_scoped_release release;
        return deform::decompose_skinning(model, clips, options);
      },
      py::arg("model"), py::arg("frames"), py::arg("max_bones") = 24, py::arg("influences") = 4,
      py::arg("iterations") = 30, py::arg("moved_tolerance") = 1e-5f, py::arg("seeds") = py::none(),
      py::arg("threads") = 0,
      "Fits extra bones and sparse weights so that linear blend skinning gives the recorded frames (a "
      "DecompositionFrames, or a list of them: one set of bones for every clip) back "
      "(docs/gltf-export.md, \"Baking bones\"). Points the artist's weights already explain keep them. Raises "
      "deform.Error for options out of range or inconsistent frames.");
  m.def(
      "decomposition_seeds",
      [](const deform::Character& character) {
        const std::vector<glm::vec3> seeds = deform::decomposition_seeds(character.deformers(), character.skeleton());
        py::array_t<float> out({static_cast<py::ssize_t>(seeds.size()), py::ssize_t{3}});
        for (std::size_t i = 0; i < seeds.size(); ++i)
          for (int k = 0; k < 3; ++k) out.mutable_data()[i * 3 + std::size_t(k)] = seeds[i][k];
        return out;
      },
      py::arg("character"),
      "(S, 3) float32: where decompose_skinning's extra bones start, one per slice of each lattice of the character.");
  m.def(
      "write_gltf",
      [](const std::string& path, const deform::Model& model, const std::vector<deform::Animation>& clips) {
        deform::GltfExportOptions options;
        options.clips = clips;
        options.generator = "libdeform " DEFORM_VERSION_STRING;
        const deform::GltfWritten written = deform::write_gltf(path, model, options);
        py::dict out;
        out["gltf"] = written.gltf;
        out["bin"] = written.bin.empty() ? py::object(py::none()) : py::object(py::str(written.bin));
        out["bytes"] = written.bytes;
        out["vertices"] = written.vertices;
        out["warnings"] = written.warnings;
        return out;
      },
      py::arg("path"), py::arg("model"), py::arg("clips") = std::vector<deform::Animation>{},
      "Writes the model as glTF 2.0 (.gltf with its .bin, or .glb), atomically: a skin with the clips "
      "(docs/gltf-export.md). Textures are left out. Returns {gltf, bin, bytes, vertices, warnings}.");
}

}  // namespace deform_python
