// rtcd.validate, rtcd.Simulation and rtcd.run: what `rtcd validate` and
// `rtcd run` do, from Python.
#include "module.hpp"
#include "rtcd/error.hpp"
#include "rtcd/sim/scene.hpp"
#include "rtcd/sim/simulation.hpp"
#include "rtcd/validation/families.hpp"
#include "rtcd/app/run.hpp"
#include "rtcd/app/validate.hpp"

namespace rtcd::python {
namespace {

std::string text_of(py::handle path) { return py::str(py::module_::import("os").attr("fspath")(path)).cast<std::string>(); }

// A scene file, or a dict holding what a scene file holds (mesh paths
// relative to the working folder).
sim::Scene scene_of(py::handle scene) {
  if (py::isinstance<py::dict>(scene)) {
    const std::string text = py::module_::import("json").attr("dumps")(scene).cast<std::string>();
    return sim::parse_scene(text, "<dict>");
  }
  return sim::load_scene(text_of(scene));
}

std::vector<size_t> device_rays(const std::vector<DeviceWork>& devices) {
  std::vector<size_t> rays;
  for (const DeviceWork& d : devices) rays.push_back(d.rays);
  return rays;
}

py::dict record_dict(const sim::StepRecord& r) {
  py::dict d(py::arg("step") = r.step, py::arg("time") = r.time, py::arg("bodies") = r.bodies,
             py::arg("seconds_broad") = r.seconds_broad, py::arg("seconds_narrow") = r.seconds_narrow,
             py::arg("seconds_solver") = r.seconds_solver, py::arg("seconds_effects") = r.seconds_effects,
             py::arg("seconds_total") = r.seconds_total, py::arg("pairs") = r.pairs,
             py::arg("pairs_full") = r.pairs_full, py::arg("pairs_iterative") = r.pairs_iterative,
             py::arg("rays_full") = r.rays.rays_full, py::arg("rays_predictive") = r.rays.rays_predictive,
             py::arg("rays_iterative") = r.rays.rays_iterative, py::arg("contacts") = r.contacts,
             py::arg("predictive") = r.predictive, py::arg("solver_points") = r.solver_points,
             py::arg("speculative_points") = r.speculative_points, py::arg("ground_contacts") = r.ground_contacts,
             py::arg("device_rays") = device_rays(r.devices), py::arg("cpu_fallback") = r.cpu_fallback,
             py::arg("kinetic_energy") = r.kinetic_energy);
  // Set on the steps the interpenetration pass ran, else None.
  auto measured = [&](double v) { return v >= 0 ? py::object(py::float_(v)) : py::none(); };
  d["interpenetration"] = measured(r.interpenetration);
  d["projected_interpenetration"] = measured(r.projected);
  d["deepest"] = measured(r.deepest);
  d["true_penetration"] = measured(r.true_penetration);
  d["deepest_true"] = measured(r.deepest_true);
  d["ground_depth_fraction"] = measured(r.ground_depth_fraction);
  d["interpenetration_pairs"] = r.interpenetration_pairs;
  d["deep_pairs"] = r.deep_pairs;
  d["longest_deep_run"] = r.longest_deep_run;
  d["longest_deep_pair"] = py::make_tuple(r.longest_deep_pair.a, r.longest_deep_pair.b);
  return d;
}

// A simulation and the scene it runs (Simulation keeps a reference to it).
struct PySimulation {
  sim::Scene scene;
  std::unique_ptr<sim::Simulation> simulation;
};

}  // namespace

void bind_experiments(py::module_& m) {
  m.def("families", &validation::family_names, "The validation families' names.");
  m.def(
      "validate",
      [](py::object family, py::object backend, const std::string& mode, size_t pairs, uint64_t seed, bool oracles,
         const py::kwargs& knobs) {
        app::ValidateOptions o;
        if (!family.is_none()) o.family = family.cast<std::string>();
        if (!backend.is_none()) o.backend = backend.cast<std::string>();
        o.mode = mode;
        if (pairs < 1) throw UsageError("pairs: expected at least 1");
        o.pairs = pairs;
        o.seed = seed;
        o.no_oracles = !oracles;
        add_knobs(knobs, o.knobs);
        o.knobs.config().validate();
        nlohmann::json result;
        {
          py::gil_scoped_release release;
          result = app::validate_json(o);
        }
        return to_python(result);
      },
      py::arg("family") = py::none(), py::arg("backend") = py::none(), py::kw_only(), py::arg("mode") = "full",
      py::arg("pairs") = 1000, py::arg("seed") = 1, py::arg("oracles") = true,
      R"(Judges backends on random pairs of validation families against the oracles, as
`rtcd validate --json` does (family, backend None: all), and returns what it
prints: one dict per family and backend. Knobs as NarrowPhase takes them.)");

  py::class_<PySimulation>(m, "Simulation", R"(A scene simulated on Bullet with rtcd's narrow phase, stepped from Python.

Simulation(scene, backend="", threads=0): scene is a scene file (docs/scenes.md)
or a dict of the same; backend overrides the scene's ("gimpact": Bullet's own).
step(steps=1) runs steps (the GIL released) and returns the last step's
record; poses, velocities and contacts are the state after it.)")
      .def(py::init([](py::handle scene, const std::string& backend, int threads) {
             auto s = std::make_unique<PySimulation>();
             s->scene = scene_of(scene);
             py::gil_scoped_release release;
             s->simulation = std::make_unique<sim::Simulation>(s->scene, backend, threads);
             return s;
           }),
           py::arg("scene"), py::arg("backend") = "", py::arg("threads") = 0)
      .def(
          "step",
          [](PySimulation& s, uint64_t steps) {
            if (steps < 1) throw UsageError("steps: expected at least 1");
            {
              py::gil_scoped_release release;
              for (uint64_t i = 0; i < steps; ++i) s.simulation->step();
            }
            return record_dict(s.simulation->last());
          },
          py::arg("steps") = 1)
      .def_property_readonly("steps_done", [](const PySimulation& s) { return s.simulation->steps_done(); })
      .def_property_readonly("record", [](const PySimulation& s) { return record_dict(s.simulation->last()); },
                             "The last step's record: counts, seconds, kinetic energy, interpenetration.")
      .def_property_readonly("backend", [](const PySimulation& s) { return s.simulation->backend(); })
      .def_property_readonly("devices", [](const PySimulation& s) { return s.simulation->devices(); })
      .def_property_readonly("labels",
                             [](const PySimulation& s) {
                               std::vector<std::string> labels;
                               for (const auto& b : s.simulation->bodies()) labels.push_back(b.label);
                               return labels;
                             })
      .def_property_readonly("poses",
                             [](const PySimulation& s) {
                               const auto bodies = s.simulation->bodies();
                               py::array_t<double> a({py::ssize_t(bodies.size()), py::ssize_t(7)});
                               for (size_t i = 0; i < bodies.size(); ++i) {
                                 const Pose& p = bodies[i].pose;
                                 const double v[7] = {p.position.x(),    p.position.y(),    p.position.z(),
                                                      p.orientation.w(), p.orientation.x(), p.orientation.y(),
                                                      p.orientation.z()};
                                 std::copy(v, v + 7, a.mutable_data(i, 0));
                               }
                               return a;
                             },
                             "(k, 7): each body's pose [tx ty tz qw qx qy qz] (its mesh file's frame)")
      .def_property_readonly("velocities",
                             [](const PySimulation& s) {
                               const auto bodies = s.simulation->bodies();
                               py::array_t<double> a({py::ssize_t(bodies.size()), py::ssize_t(6)});
                               for (size_t i = 0; i < bodies.size(); ++i)
                                 for (int k = 0; k < 3; ++k) {
                                   a.mutable_at(i, k) = bodies[i].linear_velocity[k];
                                   a.mutable_at(i, 3 + k) = bodies[i].angular_velocity[k];
                                 }
                               return a;
                             },
                             "(k, 6): linear then angular velocity")
      .def_property_readonly("masses",
                             [](const PySimulation& s) {
                               const auto bodies = s.simulation->bodies();
                               py::array_t<double> a(py::ssize_t(bodies.size()));
                               for (size_t i = 0; i < bodies.size(); ++i) a.mutable_at(i) = bodies[i].mass;
                               return a;
                             })
      .def_property_readonly(
          "contacts", [](const PySimulation& s) { return wrap_step(s.simulation->contacts()); },
          "The narrow phase's answer on the last step (a StepResult). Bodies are numbered as poses, labels, "
          "velocities and masses number them: body k is poses[k]; the ground is Simulation.GROUND.")
      .def_property_readonly("pairs",
                             [](const PySimulation& s) {
                               const auto pairs = s.simulation->pairs();
                               return py::array_t<uint32_t>({py::ssize_t(pairs.size()), py::ssize_t(2)},
                                                            reinterpret_cast<const uint32_t*>(pairs.data()));
                             },
                             "(k, 2): the pairs the last step handed the narrow phase, numbered as poses")
      .def_property_readonly("counters",
                             [](const PySimulation& s) {
                               const sim::StageCounters& c = s.simulation->counters();
                               return py::dict(py::arg("steps") = c.steps, py::arg("gravity_forces") = c.gravity_forces,
                                               py::arg("narrow_phase_batches") = c.narrow_phase_batches,
                                               py::arg("friction_points") = c.friction_points,
                                               py::arg("restitution_points") = c.restitution_points,
                                               py::arg("speculative_points") = c.speculative_points,
                                               py::arg("interpenetration_passes") = c.interpenetration_passes,
                                               py::arg("snapshots") = c.snapshots);
                             })
      .def_property_readonly("warnings", [](const PySimulation& s) { return s.simulation->warnings(); })
      .def_readonly_static("GROUND", &sim::Simulation::kGround, "The ground's number in contacts and pairs")
      .def(
          "measure_interpenetration",
          [](PySimulation& s) {
            {
              py::gil_scoped_release release;
              s.simulation->measure_interpenetration();
            }
            return record_dict(s.simulation->last());
          },
          "Runs the interpenetration pass now; the last record with its fields set.")
      .def("state_hash", [](const PySimulation& s) { return s.simulation->state_hash(); },
           "A bit-exact digest of every body's pose and velocities.");

  m.def(
      "run",
      [](py::object scene, const std::string& backend, std::optional<uint64_t> steps, int threads, py::object out,
         py::object record, bool plots, bool full_rays) {
        app::RunOptions o;
        if (!scene.is_none()) o.scene = text_of(scene);
        o.backend = backend;
        if (steps) {
          if (*steps < 1) throw UsageError("steps: expected at least 1");
          o.steps = steps;
        }
        o.threads = threads;
        if (!out.is_none()) o.out = text_of(out);
        if (!record.is_none()) o.record = text_of(record);
        o.no_plots = !plots;
        o.full_rays = full_rays;
        std::filesystem::path folder;
        int code = 0;
        {
          py::gil_scoped_release release;
          code = app::run_scene(o, &folder);
        }
        py::object summary = py::module_::import("json").attr("loads")(
            py::module_::import("pathlib").attr("Path")((folder / "summary.json").string()).attr("read_text")());
        return py::dict(py::arg("exit") = code, py::arg("folder") = folder.string(), py::arg("summary") = summary);
      },
      py::arg("scene") = py::none(), py::kw_only(), py::arg("backend") = "", py::arg("steps") = py::none(),
      py::arg("threads") = 0, py::arg("out") = py::none(), py::arg("record") = py::none(), py::arg("plots") = true,
      py::arg("full_rays") = false,
      R"(Simulates a scene as `rtcd run` does, leaving steps.csv, summary.json, plots and
snapshots in `out` (default runs/<scene>-<timestamp>/). Returns exit (0 done,
1 the simulation blew up, outputs so far kept), folder and summary (summary.json).)");
}

}  // namespace rtcd::python
