// Bézier and B-spline lattices (free-form deformation of any point cloud) and their bindings.
#include <algorithm>
#include <string>
#include <type_traits>
#include <vector>

#include "common.hpp"
#include "deform/offline/lattice_binding.hpp"
#include "deform/runtime/lattice.hpp"
#include "deform/runtime/mesh.hpp"

namespace deform_python {
namespace {

glm::ivec3 to_ivec3(const py::object& value, const char* what) {
  if (py::isinstance<py::int_>(value)) return glm::ivec3(value.cast<int>());
  const auto v = value.cast<std::vector<int>>();
  if (v.size() != 3) throw deform::Error::invalid_argument(what, "expected an int or 3 ints");
  return {v[0], v[1], v[2]};
}

py::array apply_to(const FloatArray& points, const FloatArray& uvw_or_points, auto&& each) {
  (void)points;
  const std::span<const glm::vec3> in = as_vec3(uvw_or_points, "points");
  py::array_t<float> out({static_cast<py::ssize_t>(in.size()), py::ssize_t{3}});
  auto* dst = reinterpret_cast<glm::vec3*>(out.mutable_data());
  for (std::size_t i = 0; i < in.size(); ++i) dst[i] = each(in[i]);
  return out;
}

template <class Lattice>
void bind_lattice_class(py::module_& m, const char* name, const char* counts_name, const char* doc) {
  py::class_<Lattice>(m, name, doc)
      .def(py::init([](const FloatArray& origin, const FloatArray& size, const py::object& counts) {
             const deform::LatticeFrame frame =
                 deform::LatticeFrame::axis_aligned(to_vec3(origin, "origin"), to_vec3(size, "size"));
             frame.require_valid();
             return Lattice(frame, to_ivec3(counts, "degree or point_counts"));
           }),
           py::arg("origin"), py::arg("size"),
           py::arg(counts_name) = 3 + std::is_same_v<Lattice, deform::BsplineLattice>,
           "The axis-aligned box [origin, origin + size] (size > 0 on every axis).")
      .def_static(
          "around",
          [](const FloatArray& points, const py::object& counts, float margin) {
            const std::span<const glm::vec3> p = as_vec3(points, "points");
            if (p.empty()) throw deform::Error::invalid_argument("points", "no points");
            if (!(margin >= 0.0f)) throw deform::Error::invalid_argument("margin", "must be >= 0");
            const deform::Bounds b = deform::compute_bounds(p);
            const glm::vec3 extent = glm::max(b.max - b.min, glm::vec3(1e-6f));
            const glm::vec3 pad = extent * margin + glm::vec3(1e-6f);
            const deform::LatticeFrame frame = deform::LatticeFrame::axis_aligned(b.min - pad, extent + 2.0f * pad);
            frame.require_valid();
            return Lattice(frame, to_ivec3(counts, "degree or point_counts"));
          },
          py::arg("points"), py::arg(counts_name) = 3 + std::is_same_v<Lattice, deform::BsplineLattice>,
          py::arg("margin") = 0.05f,
          "An axis-aligned lattice around (N, 3) points, padded by `margin` (fraction of the extent per axis).")
      .def_property_readonly("point_counts",
                             [](const Lattice& l) {
                               const glm::ivec3 c = l.point_counts();
                               return py::make_tuple(c.x, c.y, c.z);
                             })
      .def_property_readonly(
          "origin",
          [](const Lattice& l) { return py::make_tuple(l.frame().origin.x, l.frame().origin.y, l.frame().origin.z); })
      .def(
          "index",
          [](const Lattice& l, int i, int j, int k) {
            // The C++ index() does no range check: here an index outside the lattice raises instead of wrapping
            // round to a huge row (index(-1, 0, 0) would be 2**64 - 1).
            const glm::ivec3 c = l.point_counts();
            if (i < 0 || j < 0 || k < 0 || i >= c.x || j >= c.y || k >= c.z)
              throw py::index_error("control point (" + std::to_string(i) + ", " + std::to_string(j) + ", " +
                                    std::to_string(k) + ") is outside the lattice's point counts (" +
                                    std::to_string(c.x) + ", " + std::to_string(c.y) + ", " + std::to_string(c.z) +
                                    ")");
            return l.index(i, j, k);
          },
          py::arg("i"), py::arg("j"), py::arg("k"),
          "Row of control point (i, j, k) in control_points (i fastest). IndexError outside the point counts.")
      .def_property_readonly(
          "control_points",
          [](py::object self) {
            auto& l = self.cast<Lattice&>();
            return vec3_view(std::span<const glm::vec3>(l.control_points()), self, true);
          },
          "(P, 3) writeable view of the control points, i fastest (shares memory with the lattice).")
      .def_property_readonly(
          "rest_points",
          [](const Lattice& l) {
            const glm::ivec3 c = l.point_counts();
            std::vector<glm::vec3> rest(l.point_count());
            for (int k = 0; k < c.z; ++k)
              for (int j = 0; j < c.y; ++j)
                for (int i = 0; i < c.x; ++i) rest[l.index(i, j, k)] = l.rest_point(i, j, k);
            return vec3_copy(rest);
          },
          "(P, 3) control points at rest (a new array).")
      .def("reset", &Lattice::reset, "Every control point back to rest.")
      .def(
          "to_lattice",
          [](const Lattice& l, const FloatArray& points) {
            return apply_to(points, points, [&](glm::vec3 p) { return l.frame().to_lattice(p); });
          },
          py::arg("points"), "(u, v, w) of (N, 3) points in the lattice's box (a new array).")
      .def(
          "evaluate",
          [](const Lattice& l, const FloatArray& uvw) {
            return apply_to(uvw, uvw, [&](glm::vec3 p) { return l.evaluate(p); });
          },
          py::arg("uvw"), "The deformed position at (N, 3) lattice coordinates (a new array).")
      .def(
          "move_point",
          [](Lattice& l, const FloatArray& uvw, const FloatArray& target) {
            l.move_point(to_vec3(uvw, "uvw"), to_vec3(target, "target"));
          },
          py::arg("uvw"), py::arg("target"),
          "Direct manipulation: moves the control points least so that the point at `uvw` goes to `target`.")
      .def(
          "bind",
          [](const Lattice& l, const FloatArray& points) { return deform::bind_lattice(l, as_vec3(points, "points")); },
          py::arg("points"),
          "Binds (N, 3) points (read in place) once: the points inside the box, with their (u, v, w). Reuse the "
          "binding with deform() while the control points move.")
      .def(
          "deform",
          [](const Lattice& l, const FloatArray& points, const deform::LatticeBinding* binding) {
            const std::span<const glm::vec3> in = as_vec3(points, "points");
            deform::LatticeBinding made;
            if (binding == nullptr) {
              made = deform::bind_lattice(l, in);
              binding = &made;
            }
            py::array_t<float> out({static_cast<py::ssize_t>(in.size()), py::ssize_t{3}});
            auto* dst = reinterpret_cast<glm::vec3*>(out.mutable_data());
            std::copy(in.begin(), in.end(), dst);
            deform::LatticeEvaluateJob job;
            job.binding = binding;
            job.control_points = l.control_points();
            job.positions = {dst, in.size()};
            check(job.validate());
            {
              py::gil_scoped_release unlocked;
              check(job.run());
            }
            return out;
          },
          py::arg("points"), py::arg("binding") = py::none(),
          "The (N, 3) points deformed by the lattice (a new array; points outside the box are copied unchanged). "
          "`binding` from bind(points) saves binding on every call.");
}

}  // namespace

void bind_lattices(py::module_& m) {
  py::class_<deform::LatticeBinding>(m, "LatticeBinding", "Points bound to a lattice (from Lattice.bind).")
      .def_property_readonly("bound_count", [](const deform::LatticeBinding& b) { return b.vertex_count; })
      .def_property_readonly(
          "vertices",
          [](const deform::LatticeBinding& b) {
            std::vector<std::uint32_t> v;
            for (std::uint32_t i : b.vertices)
              if (i != deform::LatticeBinding::no_vertex) v.push_back(i);
            std::sort(v.begin(), v.end());
            return py::array_t<std::uint32_t>(static_cast<py::ssize_t>(v.size()), v.data());
          },
          "Sorted indices of the bound points (a new array).");
  bind_lattice_class<deform::BezierLattice>(
      m, "BezierLattice", "degree",
      "A Bézier volume (free-form deformation, Sederberg & Parry 1986): degree per axis 1..16 (an int or 3).");
  bind_lattice_class<deform::BsplineLattice>(
      m, "BsplineLattice", "point_counts",
      "A uniform cubic B-spline volume: control points per axis, 4..1024 (an int or 3); local control.");
}

}  // namespace deform_python
