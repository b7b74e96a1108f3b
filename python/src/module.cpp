// The extension module rtcd._rtcd: the whole library in one module (one copy
// of the static libraries and of the OpenCL state), re-exported by the
// package rtcd.
#include "module.hpp"

PYBIND11_MODULE(_rtcd, m) {
  namespace py = pybind11;
  m.doc() = R"(rtcd: ray-traced narrow-phase collision detection for concave meshes.

Meshes and shapes (Mesh, Shape, gen), the narrow phase (NarrowPhase, query,
backends, knobs), the references it is judged by (oracle), and the
experiments (validate, Simulation, run). Arrays are NumPy arrays.)";
  m.attr("__version__") = RTCD_VERSION;
  rtcd::python::bind_errors(m);
  rtcd::python::bind_meshes(m);
  rtcd::python::bind_narrow_phase(m);
  rtcd::python::bind_oracles(m);
  rtcd::python::bind_experiments(m);
}
