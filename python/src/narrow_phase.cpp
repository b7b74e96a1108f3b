// rtcd.NarrowPhase, its step results as NumPy arrays, rtcd.query,
// rtcd.backends and rtcd.knobs.
#include <array>
#include <mutex>
#include <optional>
#include <sstream>

#include "rtcd/app/inputs.hpp"
#include "module.hpp"
#include "rtcd/app/report.hpp"
#include "rtcd/backend.hpp"
#include "rtcd/error.hpp"

namespace rtcd::python {
namespace {

// Columns of a table, made from the step on first access and kept: a step
// whose arrays are never read costs no copy.
struct Table {
  std::shared_ptr<const StepResult> step;
  py::dict (*make)(const StepResult&);
  size_t rows;
  std::optional<py::dict> columns;

  const py::dict& all() {
    if (!columns) columns = make(*step);
    return *columns;
  }
  py::object column(const std::string& name) {
    const py::dict& c = all();
    if (!c.contains(name)) throw py::key_error(name);
    return c[py::str(name)];
  }
};
struct Rays : Table {};
struct Pairs : Table {};

template <class T>
py::array_t<T> column_of(size_t n, size_t cols = 1) {
  return cols == 1 ? py::array_t<T>(py::ssize_t(n)) : py::array_t<T>({py::ssize_t(n), py::ssize_t(cols)});
}

constexpr const char* kRayColumns[] = {"pair",   "source",    "source_body", "target_body",     "kind",
                                       "vertex", "edge",      "triangle",    "origin",          "direction",
                                       "normal", "depth",     "projected_depth", "push",        "distance",
                                       "predictive"};

// Contacts and/or predictive rays, one row each, with the index of their pair.
py::dict ray_columns(const StepResult& r, bool contacts, bool predictive) {
  const size_t n = (contacts ? r.contacts.size() : 0) + (predictive ? r.predictive.size() : 0);
  auto pair = column_of<int64_t>(n);
  auto source = column_of<uint8_t>(n), kind = column_of<uint8_t>(n);
  auto source_body = column_of<uint32_t>(n), target_body = column_of<uint32_t>(n), vertex = column_of<uint32_t>(n);
  auto edge = column_of<uint32_t>(n, 2);
  auto triangle = column_of<int32_t>(n);
  auto origin = column_of<double>(n, 3), direction = column_of<double>(n, 3), normal = column_of<double>(n, 3),
       push = column_of<double>(n, 3);
  auto depth = column_of<double>(n), projected = column_of<double>(n), distance = column_of<double>(n);
  auto is_predictive = column_of<bool>(n);
  // Written through raw pointers: the arrays are new, C-ordered and unchecked here.
  int64_t* pair_at = pair.mutable_data();
  uint8_t *source_at = source.mutable_data(), *kind_at = kind.mutable_data();
  uint32_t *source_body_at = source_body.mutable_data(), *target_body_at = target_body.mutable_data(),
           *vertex_at = vertex.mutable_data(), *edge_at = edge.mutable_data();
  int32_t* triangle_at = triangle.mutable_data();
  double *origin_at = origin.mutable_data(), *direction_at = direction.mutable_data(),
         *normal_at = normal.mutable_data(), *push_at = push.mutable_data(), *depth_at = depth.mutable_data(),
         *projected_at = projected.mutable_data(), *distance_at = distance.mutable_data();
  bool* predictive_at = is_predictive.mutable_data();
  auto put3 = [](double* a, size_t row, const Eigen::Vector3d& v) { std::copy(v.data(), v.data() + 3, a + 3 * row); };
  size_t row = 0;
  auto put = [&](size_t p, const RayRecord& ray) {
    pair_at[row] = int64_t(p);
    source_at[row] = uint8_t(ray.source);
    source_body_at[row] = ray.source_body;
    target_body_at[row] = ray.target_body;
    vertex_at[row] = ray.vertex;
    triangle_at[row] = ray.triangle;
    put3(origin_at, row, ray.origin);
    put3(direction_at, row, ray.direction);
    put3(normal_at, row, ray.normal);
  };
  if (contacts)
    for (size_t p = 0; p < r.pairs.size(); ++p)
      for (const Contact& c : r.contacts_of(r.pairs[p])) {
        put(p, c);
        kind_at[row] = uint8_t(c.kind);
        edge_at[2 * row] = c.edge[0];
        edge_at[2 * row + 1] = c.edge[1];
        depth_at[row] = c.depth;
        projected_at[row] = c.projected_depth;
        put3(push_at, row, c.push);
        distance_at[row] = 0.0;
        predictive_at[row] = false;
        ++row;
      }
  if (predictive)
    for (size_t p = 0; p < r.pairs.size(); ++p)
      for (const PredictiveRay& q : r.predictive_of(r.pairs[p])) {
        put(p, q);
        kind_at[row] = uint8_t(ContactKind::vertex);
        edge_at[2 * row] = edge_at[2 * row + 1] = q.vertex;
        depth_at[row] = projected_at[row] = 0.0;
        put3(push_at, row, Eigen::Vector3d::Zero());
        distance_at[row] = q.distance;
        predictive_at[row] = true;
        ++row;
      }
  py::dict d;
  const py::object columns[] = {pair,   source, source_body, target_body, kind,      vertex, edge,     triangle,
                                origin, direction, normal,   depth,       projected, push,   distance, is_predictive};
  for (size_t i = 0; i < std::size(kRayColumns); ++i) d[kRayColumns[i]] = columns[i];
  return d;
}

constexpr const char* kPairColumns[] = {"a",             "b",             "colliding",        "mode",
                                        "max_depth",     "first_contact", "contact_count",    "first_predictive",
                                        "predictive_count", "device"};

py::dict pair_columns(const StepResult& r) {
  const size_t n = r.pairs.size();
  auto a = column_of<uint32_t>(n), b = column_of<uint32_t>(n);
  auto colliding = column_of<bool>(n);
  auto mode = column_of<uint8_t>(n);
  auto max_depth = column_of<double>(n);
  auto first_contact = column_of<int64_t>(n), contact_count = column_of<int64_t>(n),
       first_predictive = column_of<int64_t>(n), predictive_count = column_of<int64_t>(n);
  auto device = column_of<int32_t>(n);
  for (size_t i = 0; i < n; ++i) {
    const PairResult& p = r.pairs[i];
    a.mutable_at(i) = p.pair.a;
    b.mutable_at(i) = p.pair.b;
    colliding.mutable_at(i) = p.colliding;
    mode.mutable_at(i) = uint8_t(p.mode);
    max_depth.mutable_at(i) = p.max_depth;
    first_contact.mutable_at(i) = int64_t(p.first_contact);
    contact_count.mutable_at(i) = int64_t(p.contact_count);
    first_predictive.mutable_at(i) = int64_t(p.first_predictive);
    predictive_count.mutable_at(i) = int64_t(p.predictive_count);
    device.mutable_at(i) = p.device;
  }
  py::dict d;
  const py::object columns[] = {a,         b,           colliding,     mode,           max_depth,
                                first_contact, contact_count, first_predictive, predictive_count, device};
  for (size_t i = 0; i < std::size(kPairColumns); ++i) d[kPairColumns[i]] = columns[i];
  return d;
}

// A step's result: the C++ StepResult, and its tables once read.
struct PyStep {
  std::shared_ptr<const StepResult> step;
  py::object pairs, contacts, predictive, rays, stats;
};

template <class T, size_t N>
void bind_table(py::module_& m, const char* name, const char* doc, const char* const (&columns)[N]) {
  auto c = py::class_<T>(m, name, doc)
               .def("__len__", [](const T& t) { return t.rows; })
               .def("keys", [](T& t) { return py::list(t.all().attr("keys")()); })
               .def("__getitem__", [](T& t, const std::string& name) { return t.column(name); })
               .def("__repr__", [name](T& t) {
                 return "<rtcd." + std::string(name) + " " + std::to_string(t.rows) +
                        " rows: " + py::str(py::list(t.all().attr("keys")())).cast<std::string>() + ">";
               });
  for (const char* column : columns)
    c.def_property_readonly(column, [column](T& t) { return t.column(column); });
}

template <class T>
py::object table(const std::shared_ptr<const StepResult>& step, py::dict (*make)(const StepResult&), size_t rows) {
  return py::cast(T{{step, make, rows, std::nullopt}});
}

// The narrow phase and a lock: one step at a time per narrow phase, taken
// with the GIL released (two narrow phases step in parallel).
struct PyNarrowPhase {
  std::unique_ptr<NarrowPhase> impl;
  std::mutex mutex;
  // Results Python has let go of, reused so a steady step keeps its buffers
  // as a C++ host's does: two, since `r = narrow.detect(...)` still holds
  // the last one while the next is made.
  std::array<std::shared_ptr<StepResult>, 2> spare;
  // A step begun (detect_begin): its pairs, copied so Python may drop its
  // array, and the result it fills; null when none runs.
  std::vector<BodyPair> begun_pairs;
  std::shared_ptr<StepResult> begun;

  std::shared_ptr<StepResult> free_result() {
    for (auto& r : spare) {
      if (!r) r = std::make_shared<StepResult>();
      if (r.use_count() == 1) return r;
    }
    return std::make_shared<StepResult>();
  }

  template <class F>
  auto locked(F&& f) {
    py::gil_scoped_release release;
    std::lock_guard lock(mutex);
    return f(*impl);
  }
};

// `text` as lines of at most 76 characters, each after `indent`.
std::string wrapped(const std::string& text, const std::string& indent) {
  std::string out, line;
  std::istringstream words(text);
  for (std::string word; words >> word;) {
    if (!line.empty() && indent.size() + line.size() + 1 + word.size() > 76) {
      out += indent + line + "\n";
      line.clear();
    }
    line += (line.empty() ? "" : " ") + word;
  }
  return out + (line.empty() ? "" : indent + line + "\n");
}

// Each knob of the table: name, kind, range and default, meaning, cost.
std::string knob_docs() {
  static constexpr const char* types[] = {"True or False", "a whole number", "a length", "'full', 'iterative' or 'auto'"};
  std::string doc;
  for (const Knob& k : knobs()) {
    std::string head = std::string(k.name) + ": " + types[int(k.type)];
    if (k.type == KnobType::count || k.type == KnobType::length)
      head += " in " + to_string(KnobValue(k.min)) + " .. " + to_string(KnobValue(k.max)) + ", or None";
    doc += "    " + head + " (default: " + k.unset + ")\n";
    doc += wrapped(std::string(k.meaning) + ". Cost: " + k.cost + ".", "        ");
  }
  return doc;
}

std::unique_ptr<NarrowPhase> make(const std::string& backend, int threads, const py::kwargs& knobs) {
  const Config config = config_of(knobs);
  BackendOptions options = BackendOptions::parse(backend);
  if (threads < 0) throw UsageError("threads: expected 0 (all cores) or more, got " + std::to_string(threads));
  if (threads > 0) options.threads = threads;
  py::gil_scoped_release release;  // an OpenCL backend compiles its program here
  return make_narrow_phase(options, config);
}

}  // namespace

py::object wrap_step(StepResult result) {
  return py::cast(PyStep{std::make_shared<const StepResult>(std::move(result)), {}, {}, {}, {}, {}});
}

void bind_narrow_phase(py::module_& m) {
  bind_table<Rays>(m, "Rays",
                   "Contacts and predictive rays of a step, one row each, grouped by pair (copies of the step's "
                   "C++ records). Columns as attributes or rays['depth']; dict(rays) for pandas.",
                   kRayColumns);
  bind_table<Pairs>(m, "Pairs", "One row per input pair, in input order (copies). mode: 0 full, 1 iterative, 2 certified.",
                    kPairColumns);

  py::class_<PyStep>(m, "StepResult", R"(What one detect() returned.

pairs: Pairs (per pair: colliding, mode, max depth, contact range).
contacts, predictive: Rays; rays: both, contacts first. Rows are grouped
by pair: a pair's contacts are contacts[first_contact : first_contact +
contact_count]. stats: the step's counters and seconds (a dict).
Each array is built on first access and kept.)")
      .def_property_readonly("pairs",
                             [](PyStep& s) {
                               if (!s.pairs) s.pairs = table<Pairs>(s.step, pair_columns, s.step->pairs.size());
                               return s.pairs;
                             })
      .def_property_readonly("contacts",
                             [](PyStep& s) {
                               if (!s.contacts)
                                 s.contacts = table<Rays>(s.step, [](const StepResult& r) { return ray_columns(r, true, false); }, s.step->contacts.size());
                               return s.contacts;
                             })
      .def_property_readonly("predictive",
                             [](PyStep& s) {
                               if (!s.predictive)
                                 s.predictive = table<Rays>(s.step, [](const StepResult& r) { return ray_columns(r, false, true); }, s.step->predictive.size());
                               return s.predictive;
                             })
      .def_property_readonly("rays",
                             [](PyStep& s) {
                               if (!s.rays)
                                 s.rays = table<Rays>(s.step, [](const StepResult& r) { return ray_columns(r, true, true); }, s.step->contacts.size() + s.step->predictive.size());
                               return s.rays;
                             })
      .def_property_readonly("stats",
                             [](PyStep& s) {
                               if (!s.stats) s.stats = to_python(app::stats_json(s.step->stats));
                               return s.stats;
                             })
      .def(
          "to_json",
          [](const PyStep& s, size_t pair) {
            if (pair >= s.step->pairs.size())
              throw py::index_error("pair " + std::to_string(pair) + " of a step of " +
                                    std::to_string(s.step->pairs.size()) + " pairs");
            StepResult one = *s.step;  // the contact ranges index the whole step's records
            one.pairs = {s.step->pairs[pair]};
            return to_python(app::to_json(one));
          },
          py::arg("pair") = 0, "One pair's result as `rtcd query --json` prints it.")
      .def("__repr__", [](const PyStep& s) {
        return "<rtcd.StepResult " + std::to_string(s.step->pairs.size()) + " pairs, " +
               std::to_string(s.step->contacts.size()) + " contacts, " + std::to_string(s.step->predictive.size()) +
               " predictive rays>";
      });

  const std::string narrow_doc = R"(A narrow phase: shapes, bodies posed in the world, and pair state that
carries from one detect() to the next, as in C++.

NarrowPhase(backend="auto", *, threads=0, **knobs)
    backend: "auto", "basic", "embree", "opencl", "opencl-basic", with
    options as the CLI takes them ("opencl:gpu:devices=0,1",
    "embree:isa=avx2"). threads > 0: the narrow phase's own thread count.
    Knobs (rtcd.knobs() lists them; None: derived per pair):
)" + knob_docs() + R"(
Poses are [tx, ty, tz, qw, qx, qy, qz]. detect(pairs) takes an (p, 2)
array of body ids: a uint32 C-ordered array is read in place, others are
converted. The GIL is released while a step runs; one narrow phase runs one
call at a time (others wait), two narrow phases run in parallel.)";

  py::class_<PyNarrowPhase>(m, "NarrowPhase", narrow_doc.c_str())
      .def(py::init([](const std::string& backend, int threads, const py::kwargs& knobs) {
             auto p = std::make_unique<PyNarrowPhase>();
             p->impl = make(backend, threads, knobs);
             return p;
           }),
           py::arg("backend") = "auto", py::kw_only(), py::arg("threads") = 0)
      .def_property_readonly("name", [](PyNarrowPhase& n) { return n.impl->name(); })
      .def_property_readonly("devices", [](PyNarrowPhase& n) { return n.impl->devices(); })
      .def_property_readonly("config",
                             [](PyNarrowPhase& n) {
                               py::dict d;
                               for (const Knob& k : knobs()) {
                                 const KnobValue v = k.get(n.impl->config());
                                 d[k.name] = std::visit(
                                     [](const auto& x) -> py::object {
                                       using X = std::decay_t<decltype(x)>;
                                       if constexpr (std::is_same_v<X, std::monostate>) return py::none();
                                       else if constexpr (std::is_same_v<X, Mode>) return py::str(to_string(x));
                                       else return py::cast(x);
                                     },
                                     v);
                               }
                               return d;
                             },
                             "The knobs, as set (None: derived per pair).")
      .def(
          "add_shape",
          [](PyNarrowPhase& n, py::handle shape) {
            auto s = shape_of(shape, "shape");
            return n.locked([&](NarrowPhase& p) { return p.add_shape(std::move(s)); });
          },
          py::arg("shape"), "Registers a Shape or a Mesh (its acceleration structures are built here); its id.")
      .def(
          "add_body",
          [](PyNarrowPhase& n, ShapeId shape, py::handle pose) {
            const Pose p = pose_of(pose, "pose");
            return n.locked([&](NarrowPhase& np) { return np.add_body(shape, p); });
          },
          py::arg("shape"), py::arg("pose") = py::none(), "A body of a registered shape; its id.")
      .def(
          "add_bodies",
          [](PyNarrowPhase& n, ShapeId shape, py::handle poses) {
            const std::vector<Pose> list = poses_of(poses, "poses");
            py::array_t<uint32_t> ids(py::ssize_t(list.size()));
            uint32_t* out = ids.mutable_data();
            n.locked([&](NarrowPhase& np) {
              for (size_t i = 0; i < list.size(); ++i) out[i] = np.add_body(shape, list[i]);
            });
            return ids;
          },
          py::arg("shape"), py::arg("poses"), "One body per row of poses (k, 7); their ids.")
      .def(
          "remove_body", [](PyNarrowPhase& n, BodyId body) { n.locked([&](NarrowPhase& p) { p.remove_body(body); }); },
          py::arg("body"), "Forgets the body and every pair state that involves it.")
      .def(
          "set_pose",
          [](PyNarrowPhase& n, BodyId body, py::handle pose) {
            const Pose p = pose_of(pose, "pose");
            n.locked([&](NarrowPhase& np) { np.set_pose(body, p); });
          },
          py::arg("body"), py::arg("pose"))
      .def(
          "set_poses",
          [](PyNarrowPhase& n, py::handle bodies, py::handle poses) {
            const auto ids = index_rows(bodies, "bodies", 1, true);
            const std::vector<Pose> list = poses_of(poses, "poses");
            if (list.size() != size_t(ids.shape(0)))
              throw UsageError("set_poses: " + std::to_string(ids.shape(0)) + " bodies but " +
                               std::to_string(list.size()) + " poses");
            const uint32_t* id = ids.data();
            n.locked([&](NarrowPhase& np) {
              for (size_t i = 0; i < list.size(); ++i) np.set_pose(id[i], list[i]);
            });
          },
          py::arg("bodies"), py::arg("poses"), "Poses (k, 7) of bodies (k,), read in place when float64 C-ordered.")
      .def(
          "detect",
          [](PyNarrowPhase& n, py::handle pairs) {
            const auto a = index_rows(pairs, "pairs", 2);
            static_assert(sizeof(BodyPair) == 2 * sizeof(uint32_t));
            const std::span<const BodyPair> list(reinterpret_cast<const BodyPair*>(a.data()), size_t(a.shape(0)));
            std::shared_ptr<StepResult> result = n.free_result();
            n.locked([&](NarrowPhase& p) { p.detect(list, *result); });
            return py::cast(PyStep{std::move(result), {}, {}, {}, {}, {}});
          },
          py::arg("pairs"),
          "One step over (p, 2) candidate pairs of body ids. Pair state carries to the next call; a pair absent "
          "from `pairs` is evicted.")
      .def(
          "detect_begin",
          [](PyNarrowPhase& n, py::handle pairs) {
            const auto a = index_rows(pairs, "pairs", 2);
            const auto* first = reinterpret_cast<const BodyPair*>(a.data());
            std::shared_ptr<StepResult> result = n.free_result();
            n.locked([&](NarrowPhase& p) {
              if (n.begun) throw UsageError("detect_begin: a step begun with detect_begin is running; call detect_end first");
              n.begun_pairs.assign(first, first + a.shape(0));
              p.detect_begin(n.begun_pairs, *result);
              n.begun = std::move(result);
            });
          },
          py::arg("pairs"),
          "detect in two halves: starts the step over (p, 2) pairs on the narrow phase's own thread and returns "
          "at once (bad pairs raise here). Python runs meanwhile; detect_end() waits and returns the StepResult. "
          "Any other call before detect_end raises.")
      .def(
          "detect_done",
          [](PyNarrowPhase& n) { return n.locked([&](NarrowPhase& p) { return p.detect_done(); }); },
          "Whether the step detect_begin started has finished (detect_end then returns at once); never waits.")
      .def(
          "detect_end",
          [](PyNarrowPhase& n) {
            std::shared_ptr<StepResult> result;
            n.locked([&](NarrowPhase& p) {
              result = std::exchange(n.begun, nullptr);
              p.detect_end();
            });
            return py::cast(PyStep{std::move(result), {}, {}, {}, {}, {}});
          },
          "Waits for the step detect_begin started and returns its StepResult (raises what the step raised).")
      .def("__repr__", [](PyNarrowPhase& n) { return "<rtcd.NarrowPhase " + n.impl->name() + ">"; });

  m.def(
      "query",
      [](py::handle a, py::handle b, py::handle pose_a, py::handle pose_b, const std::string& backend,
         const py::kwargs& knobs) {
        auto sa = shape_of(a, "a"), sb = shape_of(b, "b");
        const Pose pa = pose_of(pose_a, "pose_a"), pb = pose_of(pose_b, "pose_b");
        auto narrow = make(backend, 0, knobs);
        StepResult r;
        {
          py::gil_scoped_release release;
          const ShapeId ia = narrow->add_shape(sa), ib = sb == sa ? ia : narrow->add_shape(sb);
          const BodyPair pair{narrow->add_body(ia, pa), narrow->add_body(ib, pb)};
          narrow->detect(std::span(&pair, 1), r);
        }
        return wrap_step(std::move(r));
      },
      py::arg("a"), py::arg("b"), py::arg("pose_a") = py::none(), py::arg("pose_b") = py::none(), py::kw_only(),
      py::arg("backend") = "auto",
      "One pair, one step, as `rtcd query` does: a fresh narrow phase (knobs as NarrowPhase takes them).");

  m.def(
      "backends",
      [] {
        py::list out;
        for (const BackendInfo& b : available_backends())
          out.append(py::dict(py::arg("name") = b.name, py::arg("usable") = b.usable, py::arg("devices") = b.detail));
        return out;
      },
      "The backends built in, whether each can run here, and their devices (or why not).");

  m.def(
      "knobs",
      [] {
        static constexpr const char* types[] = {"flag", "count", "length", "mode"};
        py::list out;
        for (const Knob& k : knobs()) {
          py::dict d(py::arg("name") = k.name, py::arg("type") = types[int(k.type)], py::arg("default") = k.unset,
                     py::arg("meaning") = k.meaning, py::arg("cost") = k.cost, py::arg("effect") = k.effect);
          const bool ranged = k.type == KnobType::count || k.type == KnobType::length;
          d["min"] = ranged ? py::object(py::float_(k.min)) : py::none();
          d["max"] = ranged ? py::object(py::float_(k.max)) : py::none();
          d["off"] = k.off ? py::object(py::str(k.off)) : py::none();
          out.append(d);
        }
        return out;
      },
      "The narrow phase's knobs: name, type, range, default, meaning, cost, and for switches what turning one off "
      "does (docs/knobs.md).");
}

}  // namespace rtcd::python
