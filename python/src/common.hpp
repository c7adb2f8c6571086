#pragma once
// Shared by the binding's translation units: array conversions and the error path.
//
// Arrays in: a float32 C-contiguous (N, 3) array is read in place (a span over its buffer, no copy); any other
// layout or dtype is converted once (a copy) by pybind11's forcecast. Arrays out: views (no copy) over storage that
// the owning Python object keeps alive, or new arrays where the data has to be computed or transposed.
#include <algorithm>
#include <cstddef>
#include <cstdint>
#include <span>
#include <string>
#include <vector>

#include <glm/glm.hpp>
#include <glm/gtc/quaternion.hpp>
#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>
#include <pybind11/stl.h>

#include "deform/runtime/error.hpp"
#include "deform/runtime/skeleton.hpp"

namespace deform_python {

namespace py = pybind11;

using FloatArray = py::array_t<float, py::array::c_style | py::array::forcecast>;

// A refused per-frame call (deform::Status): the translator raises deform.Error with kind "status".
struct StatusFailure {
  const char* reason;
};

inline void check(deform::Status status) {
  if (!status) throw StatusFailure{status.reason()};
}

// (N, width) float32 rows of `array`, N = rows; throws deform::Error (argument) naming `what` otherwise.
inline std::size_t rows_of(const FloatArray& array, py::ssize_t width, const char* what) {
  if (array.ndim() != 2 || array.shape(1) != width)
    throw deform::Error::invalid_argument(what, "expected an array of shape (N, " + std::to_string(width) + ")");
  return static_cast<std::size_t>(array.shape(0));
}

inline std::span<const glm::vec3> as_vec3(const FloatArray& array, const char* what) {
  const std::size_t n = rows_of(array, 3, what);
  return {reinterpret_cast<const glm::vec3*>(array.data()), n};
}

inline glm::vec3 to_vec3(const FloatArray& array, const char* what) {
  if (array.size() != 3) throw deform::Error::invalid_argument(what, "expected 3 numbers");
  return {array.data()[0], array.data()[1], array.data()[2]};
}

// A view of `count` × `width` values of T at `data`, kept alive by `owner`; read-only unless `writeable`.
template <class T>
py::array view(const T* data, std::size_t count, std::size_t width, py::handle owner, bool writeable) {
  py::array out(py::dtype::of<T>(), {static_cast<py::ssize_t>(count), static_cast<py::ssize_t>(width)},
                {static_cast<py::ssize_t>(width * sizeof(T)), static_cast<py::ssize_t>(sizeof(T))}, data, owner);
  if (!writeable) out.attr("flags").attr("writeable") = false;
  return out;
}

inline py::array vec3_view(std::span<const glm::vec3> v, py::handle owner, bool writeable) {
  return view(v.empty() ? nullptr : &v[0].x, v.size(), 3, owner, writeable);
}

// A new array with a copy of `values`: (N / width, width), or (N,) for width 1.
template <class T>
py::array copy_array(std::span<const T> values, std::size_t width) {
  std::vector<py::ssize_t> shape{static_cast<py::ssize_t>(values.size() / width)};
  if (width > 1) shape.push_back(static_cast<py::ssize_t>(width));
  py::array_t<T> out(shape);
  std::copy(values.begin(), values.end(), out.mutable_data());
  return out;
}
template <class T>
py::array copy_array(const std::vector<T>& values, std::size_t width) {
  return copy_array(std::span<const T>(values), width);
}

// New (N, 3) float32 array with a copy of `v`.
inline py::array vec3_copy(std::span<const glm::vec3> v) {
  py::array_t<float> out({static_cast<py::ssize_t>(v.size()), py::ssize_t{3}});
  float* dst = out.mutable_data();
  for (std::size_t i = 0; i < v.size(); ++i) {
    dst[3 * i] = v[i].x;
    dst[3 * i + 1] = v[i].y;
    dst[3 * i + 2] = v[i].z;
  }
  return out;
}

// (B, 4, 4) float32, row-major mathematical convention (out[b, row, col]) from glm's column-major matrices.
inline py::array matrices_out(std::span<const glm::mat4> m) {
  py::array_t<float> out({static_cast<py::ssize_t>(m.size()), py::ssize_t{4}, py::ssize_t{4}});
  float* dst = out.mutable_data();
  for (std::size_t b = 0; b < m.size(); ++b)
    for (int r = 0; r < 4; ++r)
      for (int c = 0; c < 4; ++c) dst[16 * b + static_cast<std::size_t>(4 * r + c)] = m[b][c][r];
  return out;
}

// A bone given by id or name; deform::Error (argument) naming it when `skeleton` has no such bone.
std::int32_t resolve_bone(const deform::Skeleton& skeleton, const py::object& bone);
// glm matrices from (B, 4, 4) row-major float32 (a copy: glm stores columns).
std::vector<glm::mat4> matrices_in(const FloatArray& a);

// Each part of the module, in the order PYBIND11_MODULE (module.cpp) registers them.
void bind_skeleton(py::module_& m);
void bind_model(py::module_& m);
void bind_rig(py::module_& m);
void bind_automatic_weights(py::module_& m);
void bind_import_export(py::module_& m);
void bind_simplify(py::module_& m);
void bind_animation(py::module_& m);
void bind_blending(py::module_& m);
void bind_jobs(py::module_& m);
void bind_lattices(py::module_& m);
void bind_character(py::module_& m);
void bind_weight_tools(py::module_& m);
void bind_decomposition(py::module_& m);
void bind_correctives(py::module_& m);

}  // namespace deform_python
