// The library's typed errors (framework/error.hpp) as Python exceptions of matching types, carrying
// the C++ message:
//
//   driftlab.Error               (RuntimeError)         base of all
//   driftlab.ConfigError         (Error, ValueError)    .problems: [{file, line, field, message}, ...]
//   driftlab.UnknownPluginError  (ConfigError)
//   driftlab.DataError           (Error, ValueError)    .file, .line, .field
//   driftlab.NotFittedError      (Error)
//
// Other C++ exceptions keep pybind11's mapping (std::invalid_argument -> ValueError, ...).
#pragma once

#include <pybind11/pybind11.h>

namespace driftlab::python {

namespace py = pybind11;

// Adds the classes to `m` and registers the translator.
void register_errors(py::module_& m);

}  // namespace driftlab::python
