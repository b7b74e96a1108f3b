// What the parts of the extension module rtcd._rtcd share: the Python side
// of a mesh, conversions of NumPy arrays (checked, naming the argument),
// poses, knobs and JSON.
#pragma once

#include <memory>
#include <string>

#include <nlohmann/json.hpp>
#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>
#include <pybind11/stl.h>
#include <pybind11/stl/filesystem.h>

#include "rtcd/config.hpp"
#include "rtcd/geometry.hpp"
#include "rtcd/results.hpp"
#include "rtcd/shape.hpp"

namespace rtcd::app {
struct Knobs;
}

namespace rtcd::python {

namespace py = pybind11;

// A mesh as Python sees it: the shape made of it, so a mesh is added to a
// narrow phase, an oracle or a query as it is, its arrays views into it.
struct PyMesh {
  std::shared_ptr<const Shape> shape;
  const Mesh& mesh() const { return *shape->mesh(); }
};

// A Shape or a Mesh.
std::shared_ptr<const Shape> shape_of(py::handle object, const char* name);

// An (n, cols) array (or (cols,) when `vector`) of finite numbers as
// float64, C order; copied only when its type or layout differ.
py::array_t<double, py::array::c_style> float_rows(py::handle object, const char* name, py::ssize_t cols,
                                                   bool vector = false);
// An (n, cols) array (or (n,) when `vector` and cols is 1) of integers in
// [0, 2^32) as uint32, C order; copied only when its type or layout differ.
py::array_t<uint32_t, py::array::c_style> index_rows(py::handle object, const char* name, py::ssize_t cols,
                                                     bool vector = false);

// [tx, ty, tz, qw, qx, qy, qz] (the CLI's order), checked as the CLI does;
// None: the identity.
Pose pose_of(py::handle object, const char* name);
// One pose per row of a (k, 7) array; errors name the row.
std::vector<Pose> poses_of(py::handle object, const char* name);
py::array_t<double> pose_array(const Pose& pose);

// Keyword arguments named as the knobs of rtcd::knobs(): ConfigError for
// an unknown name or a value of the wrong kind.
void add_knobs(const py::kwargs& kwargs, app::Knobs& knobs);
Config config_of(const py::kwargs& kwargs);

// JSON as Python's dicts, lists, numbers and strings.
py::object to_python(const nlohmann::json& json);

// Read-only view of `count` rows of `cols` T at `data`, keeping `owner` alive.
template <class T>
py::array_t<T> view(const T* data, size_t count, size_t cols, py::handle owner) {
  py::array_t<T> a({py::ssize_t(count), py::ssize_t(cols)}, data, owner);
  py::detail::array_proxy(a.ptr())->flags &= ~py::detail::npy_api::NPY_ARRAY_WRITEABLE_;
  return a;
}

// The parts of the module, each adding its names.
void bind_errors(py::module_& m);
void bind_meshes(py::module_& m);
void bind_narrow_phase(py::module_& m);
void bind_oracles(py::module_& m);
void bind_experiments(py::module_& m);

// A step's result as Python sees it (narrow_phase.cpp).
py::object wrap_step(StepResult result);

}  // namespace rtcd::python
