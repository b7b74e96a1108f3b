// Checked conversions from Python (arrays, poses, knobs), JSON to Python,
// and rtcd's errors as Python exceptions.
#include <cmath>
#include <cstring>
#include <sstream>

#include "rtcd/app/inputs.hpp"
#include "module.hpp"
#include "rtcd/error.hpp"
#include "rtcd/sim/recording.hpp"
#include "rtcd/sim/scene.hpp"
#include "rtcd/sim/simulation.hpp"

namespace rtcd::python {
namespace {

std::string shape_text(const py::array& a) {
  std::ostringstream s;
  s << '(';
  for (py::ssize_t i = 0; i < a.ndim(); ++i) s << (i ? ", " : "") << a.shape(i);
  s << (a.ndim() == 1 ? ",)" : ")");
  return s.str();
}

// np.asarray(object), with its kind of element one of `kinds` ("fiu": floats
// or integers), else TypeError naming the argument.
py::array numeric(py::handle object, const char* name, const char* kinds, const char* wanted) {
  py::array a;
  try {
    // An array is taken as it is: most calls pass one, and np.asarray costs a call.
    a = py::isinstance<py::array>(object) ? py::reinterpret_borrow<py::array>(object)
                                          : py::array(py::module_::import("numpy").attr("asarray")(object));
  } catch (const py::error_already_set&) {
    throw py::type_error(std::string(name) + ": expected " + wanted);
  }
  const char kind = a.dtype().kind();
  if (!std::strchr(kinds, kind))
    throw py::type_error(std::string(name) + ": expected " + wanted + ", got an array of " +
                         py::str(a.dtype()).cast<std::string>());
  return a;
}

void expect_rows(const py::array& a, const char* name, py::ssize_t cols, bool vector) {
  const bool rows = a.ndim() == 2 && a.shape(1) == cols;
  if (rows || (vector && a.ndim() == 1 && a.shape(0) == cols)) return;
  throw UsageError(std::string(name) + ": expected shape " + (vector ? "(" + std::to_string(cols) + ",) or " : "") +
                   "(n, " + std::to_string(cols) + "), got " + shape_text(a));
}

}  // namespace

py::array_t<double, py::array::c_style> float_rows(py::handle object, const char* name, py::ssize_t cols,
                                                   bool vector) {
  py::array a = numeric(object, name, "fiu", "an array of numbers");
  expect_rows(a, name, cols, vector);
  auto out = py::array_t<double, py::array::c_style | py::array::forcecast>::ensure(a);
  const double* v = out.data();
  for (py::ssize_t i = 0; i < out.size(); ++i)
    if (!std::isfinite(v[i])) {
      std::ostringstream s;
      s << name << ": " << (out.ndim() == 2 ? "row " + std::to_string(i / cols) + " " : "") << "holds " << v[i]
        << ", not a finite number";
      throw UsageError(s.str());
    }
  return out;
}

py::array_t<uint32_t, py::array::c_style> index_rows(py::handle object, const char* name, py::ssize_t cols,
                                                     bool vector) {
  py::array a = numeric(object, name, "iu", "an array of integers");
  if (a.ndim() == 1 && a.shape(0) == 0) a = a.attr("reshape")(0, cols);  // [] : no rows
  if (vector && a.ndim() == 1) {
    if (cols != 1) throw UsageError(std::string(name) + ": expected shape (n,), got " + shape_text(a));
  } else {
    expect_rows(a, name, cols, false);
  }
  if (a.dtype().is(py::dtype::of<uint32_t>()) && (a.flags() & py::array::c_style))
    return py::reinterpret_borrow<py::array_t<uint32_t, py::array::c_style>>(a);
  py::array_t<uint32_t, py::array::c_style> out(std::vector<py::ssize_t>(a.shape(), a.shape() + a.ndim()));
  uint32_t* o = out.mutable_data();
  // Through the widest integer of the array's signedness, so no value wraps.
  auto narrow = [&]<class Wide>(Wide) {
    const auto wide = py::array_t<Wide, py::array::c_style | py::array::forcecast>::ensure(a);
    const Wide* in = wide.data();
    for (py::ssize_t i = 0; i < wide.size(); ++i) {
      if (in[i] < 0 || uint64_t(in[i]) > UINT32_MAX)
        throw UsageError(std::string(name) + ": row " + std::to_string(i / cols) + " holds " + std::to_string(in[i]) +
                         ", not an id in [0, 2^32)");
      o[i] = uint32_t(in[i]);
    }
  };
  if (a.dtype().kind() == 'u') narrow(uint64_t{});
  else narrow(int64_t{});
  return out;
}

Pose pose_of(py::handle object, const char* name) {
  if (object.is_none()) return Pose{};
  const auto a = float_rows(object, name, 7, true);
  if (a.ndim() != 1) throw UsageError(std::string(name) + ": expected one pose of 7 numbers, got " + shape_text(a));
  return app::pose_from(a.data(), name);
}

std::vector<Pose> poses_of(py::handle object, const char* name) {
  const auto a = float_rows(object, name, 7);
  std::vector<Pose> poses(size_t(a.shape(0)));
  for (size_t i = 0; i < poses.size(); ++i) poses[i] = app::pose_from(a.data(i, 0), std::string(name) + ": row " + std::to_string(i));
  return poses;
}

py::array_t<double> pose_array(const Pose& p) {
  return py::array_t<double>(7, std::array{p.position.x(), p.position.y(), p.position.z(), p.orientation.w(),
                                           p.orientation.x(), p.orientation.y(), p.orientation.z()}
                                    .data());
}

std::shared_ptr<const Shape> shape_of(py::handle object, const char* name) {
  if (py::isinstance<PyMesh>(object)) return object.cast<const PyMesh&>().shape;
  if (py::isinstance<Shape>(object)) return object.cast<std::shared_ptr<Shape>>();
  throw py::type_error(std::string(name) + ": expected an rtcd.Shape or an rtcd.Mesh, got " +
                       py::str(py::type::of(object).attr("__name__")).cast<std::string>());
}

void add_knobs(const py::kwargs& kwargs, app::Knobs& knobs) {
  for (const auto& [key, value] : kwargs) {
    const std::string name = key.cast<std::string>();
    const Knob* knob = find_knob(name);
    if (!knob) {
      std::string names;
      for (const Knob& k : rtcd::knobs()) names += (names.empty() ? "" : ", ") + std::string(k.name);
      throw ConfigError("unknown knob '" + name + "' (knobs: " + names + ")");
    }
    KnobValue v;
    if (value.is_none()) v = std::monostate{};
    else if (py::isinstance<py::bool_>(value)) v = value.cast<bool>();
    else if (py::isinstance<py::int_>(value) || py::isinstance<py::float_>(value)) v = value.cast<double>();
    else if (py::isinstance<py::str>(value) && knob->type == KnobType::mode) v = parse_mode(value.cast<std::string>());
    else
      throw py::type_error(name + ": got " + py::str(py::type::of(value).attr("__name__")).cast<std::string>() +
                           ", expected " + (knob->type == KnobType::flag   ? "True or False"
                                            : knob->type == KnobType::mode ? "'full', 'iterative' or 'auto'"
                                                                           : "a number or None"));
    Config probe;
    knob->set(probe, v);  // the knob's own check of the kind of value
    knobs.set.push_back({knob, v});
  }
}

Config config_of(const py::kwargs& kwargs) {
  app::Knobs knobs;
  add_knobs(kwargs, knobs);
  Config c = knobs.config();
  c.validate();
  return c;
}

py::object to_python(const nlohmann::json& json) {
  // Kept for the process's life: a static py::object would be released
  // after the interpreter is gone.
  static const py::handle loads = py::object(py::module_::import("json").attr("loads")).release();
  return loads(json.dump());
}

void bind_errors(py::module_& m) {
  // One class per kind of error; those that blame the input are ValueErrors.
  auto make = [&](const char* name, py::tuple bases, const char* doc) {
    PyObject* type = PyErr_NewExceptionWithDoc((std::string("rtcd.") + name).c_str(), doc, bases.ptr(), nullptr);
    if (!type) throw py::error_already_set();
    m.attr(name) = py::reinterpret_steal<py::object>(type);
    return type;  // the module keeps it
  };
  static PyObject* error = make("Error", py::make_tuple(py::handle(PyExc_RuntimeError)), "Any error rtcd reports.");
  static PyObject* mesh = make("MeshError", py::make_tuple(py::handle(error), py::handle(PyExc_ValueError)),
                               "A mesh rtcd cannot use: .kind names why, .vertex and .triangle where (or None).");
  static PyObject* config = make("ConfigError", py::make_tuple(py::handle(error), py::handle(PyExc_ValueError)),
                                 "A knob out of range or of the wrong kind.");
  static PyObject* usage = make("UsageError", py::make_tuple(py::handle(error), py::handle(PyExc_ValueError)),
                                "An argument rtcd cannot use: an unknown body, a bad pose, a bad array.");
  static PyObject* backend =
      make("BackendError", py::make_tuple(py::handle(error)), "A backend that is unknown or cannot run here.");
  static PyObject* simulation =
      make("SimulationError", py::make_tuple(py::handle(error)), "A simulation that blew up (the step and the body).");
  static PyObject* scene = make("SceneError", py::make_tuple(py::handle(error), py::handle(PyExc_ValueError)),
                                "A scene file rtcd cannot run: the file and the key path.");
  static PyObject* recording = make("RecordingError", py::make_tuple(py::handle(error), py::handle(PyExc_ValueError)),
                                    "A recording rtcd cannot read: the file, the step, what.");
  py::register_exception_translator([](std::exception_ptr thrown) {
    auto raise = [](PyObject* type, const char* message) { PyErr_SetString(type, message); };
    try {
      std::rethrow_exception(thrown);
    } catch (const MeshError& e) {
      py::object instance = py::reinterpret_borrow<py::object>(mesh)(e.what());
      instance.attr("kind") = to_string(e.kind());
      instance.attr("vertex") = e.vertex() ? py::object(py::int_(*e.vertex())) : py::none();
      instance.attr("triangle") = e.triangle() ? py::object(py::int_(*e.triangle())) : py::none();
      PyErr_SetObject(mesh, instance.ptr());
    } catch (const ConfigError& e) {
      raise(config, e.what());
    } catch (const UsageError& e) {
      raise(usage, e.what());
    } catch (const BackendError& e) {
      raise(backend, e.what());
    } catch (const sim::SimulationError& e) {
      raise(simulation, e.what());
    } catch (const sim::SceneError& e) {
      raise(scene, e.what());
    } catch (const sim::RecordingError& e) {
      raise(recording, e.what());
    } catch (const Error& e) {
      raise(error, e.what());
    }
  });
}

}  // namespace rtcd::python
