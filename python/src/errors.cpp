// radmesh's errors as Python exceptions, for both extension modules.

#include "python/src/types.h"

#include "radmesh/errors.h"

#include <pybind11/stl.h>

namespace radmesh::python {

namespace {

// The exception class `name` of radmesh._core, raised with the message;
// the options the error names go with it (e.options), as the keywords
// radmesh.solve takes.
void raise(const char* name, const Error& e) {
  const py::object type = py::module_::import("radmesh._core").attr(name);
  py::object err = type(text(e.what()));
  err.attr("options") = py::cast(e.options());
  PyErr_SetObject(type.ptr(), err.ptr());
}

}  // namespace

py::str text(const std::string& s) {
  return py::reinterpret_steal<py::str>(PyUnicode_DecodeUTF8(s.data(), static_cast<Py_ssize_t>(s.size()), "replace"));
}

py::list texts(const std::vector<std::string>& v) {
  py::list l;
  for (const std::string& s : v) l.append(text(s));
  return l;
}

void translate_errors(py::module_) {
  py::register_exception_translator([](std::exception_ptr p) {
    try {
      if (p) std::rethrow_exception(p);
    } catch (const InputError& e) {
      raise("InputError", e);
    } catch (const GeometryError& e) {
      raise("GeometryError", e);
    } catch (const NumericalError& e) {
      raise("NumericalError", e);
    } catch (const IoError& e) {
      raise("IoError", e);
    } catch (const Error& e) {
      raise("Error", e);
    }
  });
}

}  // namespace radmesh::python
