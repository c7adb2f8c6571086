// The `deform` Python module: its doc and error type, then every part's bindings in registration order (a class
// is registered before the functions whose signatures name it, so their docstrings show its Python name).
#include <exception>
#include <string>

#include "common.hpp"

namespace deform_python {
namespace {

py::object error_type;  // deform.Error, set once at import

void raise(const std::string& what, py::object kind, py::object message, py::object file, py::object line,
           py::object byte, py::object element) {
  py::object instance = error_type(what);
  instance.attr("kind") = std::move(kind);
  instance.attr("message") = std::move(message);
  instance.attr("file") = std::move(file);
  instance.attr("line") = std::move(line);
  instance.attr("byte") = std::move(byte);
  instance.attr("element") = std::move(element);
  PyErr_SetObject(error_type.ptr(), instance.ptr());
}

py::object or_none(const std::string& s) { return s.empty() ? py::object(py::none()) : py::object(py::str(s)); }

void translate(std::exception_ptr pointer) {
  try {
    if (pointer) std::rethrow_exception(pointer);
  } catch (const deform::Error& e) {
    const char* kind = e.kind() == deform::Error::Kind::input      ? "input"
                       : e.kind() == deform::Error::Kind::argument ? "argument"
                                                                   : "environment";
    const py::object position = py::int_(e.position());
    raise(e.what(), py::str(kind), py::str(e.message()), or_none(e.file()),
          e.where() == deform::Error::Where::line ? position : py::none(),
          e.where() == deform::Error::Where::byte ? position : py::none(), or_none(e.element()));
  } catch (const StatusFailure& failure) {
    raise(failure.reason, py::str("status"), py::str(failure.reason), py::none(), py::none(), py::none(), py::none());
  }
}

void bind_error(py::module_& m) {
  error_type = py::reinterpret_borrow<py::object>(
      PyErr_NewExceptionWithDoc("deform.Error",
                                "libdeform's error (deform::Error, or a refused per-frame call).\n\n"
                                "str(e) is libdeform's one-line message. Attributes: kind ('input': a file or data "
                                "is bad; 'argument': an argument is invalid; 'status': a per-frame call refused), "
                                "message (without the location), file, line (1-based, text formats), byte (offset, "
                                "binary formats), element ('bone 3', 'vertex 17'); None where they do not apply.",
                                PyExc_ValueError, nullptr));
  m.attr("Error") = error_type;
  py::register_exception_translator(&translate);
}

}  // namespace
}  // namespace deform_python

using namespace deform_python;

PYBIND11_MODULE(deform, m) {
  m.doc() =
      "libdeform on NumPy: skinning, IK, Bezier/B-spline lattices, elastic lattices and the Character.\n\n"
      "Arrays are float32. A C-contiguous float32 (N, 3) input is read in place; anything else is converted "
      "(one copy). Properties documented as views share memory with their object and keep it alive.";

  bind_error(m);
  bind_skeleton(m);
  bind_model(m);
  bind_rig(m);
  bind_automatic_weights(m);
  bind_import_export(m);
  bind_simplify(m);
  bind_animation(m);
  bind_blending(m);
  bind_jobs(m);
  bind_lattices(m);
  bind_correctives(m);  // before the Character, whose add_pose_driver takes a PoseDriver
  bind_character(m);
  bind_weight_tools(m);
  bind_decomposition(m);
}
