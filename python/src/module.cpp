// The compiled part of the `driftlab` Python package (python/driftlab/__init__.py is the rest): the
// typed errors, the plugin registry and the adapters of python/src/*.cpp.
#include <pybind11/pybind11.h>

#include "python/src/bindings.hpp"
#include "python/src/errors.hpp"

PYBIND11_MODULE(_driftlab, m) {
  m.doc() = "driftlab's library for Python (import driftlab, not this module)";
  m.attr("__version__") = DRIFTLAB_VERSION;
  driftlab::python::register_errors(m);
  driftlab::python::bind_plugins(m);
  driftlab::python::bind_allan(m);
  driftlab::python::bind_data(m);
}
