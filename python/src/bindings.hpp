// The adapters of the `_driftlab` module, one function per area. Each converts Python arguments
// (python/src/convert.hpp), calls the library with the GIL released, and returns numpy arrays and
// small result objects whose field names carry their units.
#pragma once

#include <pybind11/pybind11.h>

namespace driftlab {
class Registry;
}

namespace driftlab::python {

namespace py = pybind11;

// The module's registry: the built-in plugins, then the libraries of $DRIFTLAB_PLUGIN_PATH (as the
// command line), made on first use.
const Registry& registry();

void bind_plugins(py::module_& m);  // plugin tables, decompositions, sample entropy (plugins.cpp)
void bind_allan(py::module_& m);    // Allan deviation and its readings (allan.cpp)
void bind_data(py::module_& m);     // records, devices, calibration models, pipelines (data.cpp)
}  // namespace driftlab::python
