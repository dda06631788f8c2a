// Between Python objects and the library's types, for the bindings' thin adapters.
//
// Inputs: any array-like of numbers becomes float64 (numpy converts lists and other dtypes; a
// C-contiguous float64 array is read in place, without a copy). Every sample must be finite: the
// first NaN or Inf is a DataError naming the argument and the sample's index, as the CSV reader
// names the cell.
// Outputs: the Eigen storage a kernel returned is moved into a capsule owned by the numpy array, so
// results are never copied. A samples x K matrix (column-major, one component per column) is
// returned with shape (K, samples), one component per row, C-contiguous: the layout of PyEMD's
// IMFs and of the matrix's own memory.
// Parameters: keyword arguments become a YAML map and go through the plugin's parameter table
// (framework/params_io.hpp), the path pipeline files and `--set` take, so defaults, conversions,
// constraints and messages are the table's.
#pragma once

#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>

#include <Eigen/Core>
#include <nlohmann/json.hpp>
#include <string>

#include "framework/params.hpp"

namespace driftlab {
class Registry;
}

namespace driftlab::python {

namespace py = pybind11;

// Array-likes converted to C-contiguous float64 by numpy (no copy when they already are).
using InputArray = py::array_t<double, py::array::c_style | py::array::forcecast>;

// The samples of a 1-D input, read in place (valid while `array` lives). DataError naming `name`
// when it is not 1-D or a sample is not finite.
Eigen::Map<const Eigen::VectorXd> vector_view(const InputArray& array, const char* name);

// A vector of n samples without a copy; a matrix as (columns, rows) without a copy.
py::array to_numpy(Eigen::VectorXd&& values);
py::array columns_to_numpy(Eigen::MatrixXd&& columns);

// JSON (run reports, plugin diagnostics) as dicts, lists, numbers, strings, bools and None.
py::object to_python(const nlohmann::json& value);
// A parameter value (default or resolved) as a Python value; a nested plugin as
// {"plugin": name, "params": {...}}.
py::object to_python(const ParamValue& value);

// Validated parameters of `plugin` from keyword arguments (defaults filled in from its table).
// ConfigError listing every problem: unknown keys (naming the valid ones), wrong types, values
// outside the constraints, broken cross-parameter rules.
ParamValues resolve_keyword_params(const Registry& registry, const std::string& plugin, const py::dict& params);

}  // namespace driftlab::python
