#include "python/src/errors.hpp"

#include "framework/error.hpp"

namespace driftlab::python {
namespace {

// The exception classes, created once when the module is imported and kept for the interpreter's
// life (as pybind11's own registered exceptions are).
struct Classes {
  PyObject* error = nullptr;
  PyObject* config = nullptr;
  PyObject* data = nullptr;
  PyObject* unknown_plugin = nullptr;
  PyObject* not_fitted = nullptr;
};
Classes classes;

PyObject* new_class(py::module_& m, const char* name, const char* doc, py::tuple bases) {
  const std::string qualified = std::string("driftlab.") + name;
  PyObject* cls = PyErr_NewExceptionWithDoc(qualified.c_str(), doc, bases.ptr(), nullptr);
  if (cls == nullptr) throw py::error_already_set();
  m.add_object(name, py::handle(cls));  // the module's reference; `classes` keeps a borrowed one
  return cls;
}

py::dict location(const Location& where) {
  py::dict d;
  d["file"] = where.file;
  d["line"] = where.line;
  d["field"] = where.field;
  return d;
}

// Raises an instance of `cls` carrying the C++ message and, as attributes, where the problem is.
void raise(PyObject* cls, const char* message, const py::dict& attributes) {
  py::object instance = py::reinterpret_borrow<py::object>(cls)(message);
  for (const auto& [k, v] : attributes) instance.attr(k) = v;
  PyErr_SetObject(cls, instance.ptr());
}

void raise_config(PyObject* cls, const ConfigError& e) {
  py::list problems;
  for (const auto& p : e.problems()) {
    py::dict d = location(p.where);
    d["message"] = p.message;
    problems.append(d);
  }
  py::dict attributes;
  attributes["problems"] = problems;
  raise(cls, e.what(), attributes);
}

}  // namespace

void register_errors(py::module_& m) {
  const py::handle value_error(PyExc_ValueError), runtime_error(PyExc_RuntimeError);
  classes.error =
      new_class(m, "Error", "Base of every error the driftlab library raises.", py::make_tuple(runtime_error));
  classes.config =
      new_class(m, "ConfigError",
                "Bad configuration: a parameter, a pipeline, a device file, a calibration file. `problems` lists every "
                "problem found, each a dict with file, line (1-based, 0 unknown), field and message.",
                py::make_tuple(py::handle(classes.error), value_error));
  classes.data = new_class(
      m, "DataError",
      "Bad input data: a non-finite sample, a record too short, a CSV cell. `file`, `line` and `field` say where.",
      py::make_tuple(py::handle(classes.error), value_error));
  classes.unknown_plugin =
      new_class(m, "UnknownPluginError", "A plugin name the registry does not know, or a library that is not a plugin.",
                py::make_tuple(py::handle(classes.config)));
  classes.not_fitted =
      new_class(m, "NotFittedError", "A model used before it was fitted.", py::make_tuple(py::handle(classes.error)));

  py::register_exception_translator([](std::exception_ptr p) {
    try {
      if (p) std::rethrow_exception(p);
    } catch (const UnknownPluginError& e) {
      raise_config(classes.unknown_plugin, e);
    } catch (const ConfigError& e) {
      raise_config(classes.config, e);
    } catch (const DataError& e) {
      raise(classes.data, e.what(), location(e.where()));
    } catch (const NotFittedError& e) {
      raise(classes.not_fitted, e.what(), {});
    } catch (const Error& e) {
      raise(classes.error, e.what(), {});
    }
  });
}

}  // namespace driftlab::python
