// rtcd.Mesh, rtcd.Shape, rtcd.gen and the mesh checker.
#include "rtcd/app/check.hpp"
#include "module.hpp"
#include "rtcd/error.hpp"
#include "rtcd/mesh_check.hpp"
#include "rtcd/mesh_gen.hpp"

namespace rtcd::python {
namespace {

PyMesh wrap(Mesh mesh) { return {std::make_shared<const Shape>(std::move(mesh))}; }

MeshData data_of(py::handle vertices, py::handle triangles) {
  const auto v = float_rows(vertices, "vertices", 3);
  const auto t = index_rows(triangles, "triangles", 3);
  MeshData d;
  d.positions.resize(size_t(v.shape(0)));
  for (size_t i = 0; i < d.positions.size(); ++i)  // single precision, as the file loaders store them
    d.positions[i] = Eigen::Vector3d(v.at(i, 0), v.at(i, 1), v.at(i, 2)).cast<float>();
  d.triangles.resize(size_t(t.shape(0)));
  std::memcpy(d.triangles.data(), t.data(), d.triangles.size() * sizeof(Mesh::Triangle));
  return d;
}

PyMesh mesh_of(py::handle vertices, py::handle triangles, bool weld, bool allow_zero_area) {
  MeshData d = data_of(vertices, triangles);
  MeshOptions options;
  options.weld = weld;
  options.allow_zero_area = allow_zero_area;
  return wrap(Mesh(std::move(d.positions), std::move(d.triangles), options));
}

py::array_t<double> bounds_array(const Aabb& b) {
  py::array_t<double> a({2, 3});
  for (int k = 0; k < 3; ++k) {
    a.mutable_at(0, k) = b.min[k];
    a.mutable_at(1, k) = b.max[k];
  }
  return a;
}

// An Eigen::Vector3f is three packed floats: a vector of them is an (n, 3) array.
static_assert(sizeof(Eigen::Vector3f) == 3 * sizeof(float) && sizeof(Mesh::Triangle) == 3 * sizeof(uint32_t) &&
              sizeof(Mesh::Neighbors) == 3 * sizeof(int32_t));
template <class Row, class T = std::remove_cvref_t<decltype(std::declval<Row>()[0])>>
py::array_t<T> rows_view(std::span<const Row> rows, py::handle owner) {
  return view(reinterpret_cast<const T*>(rows.data()), rows.size(), 3, owner);
}

const char* kind_of(const Shape& s) {
  static constexpr const char* names[] = {"mesh", "sphere", "box", "half_space"};
  return names[s.geometry().index()];
}

}  // namespace

void bind_meshes(py::module_& m) {
  py::class_<PyMesh>(m, "Mesh", R"(A validated triangle mesh: ids are the caller's (or the file's).

Mesh(vertices, triangles, *, weld=False, allow_zero_area=False)
    vertices: (n, 3) numbers, stored in single precision as the file
    loaders store them; triangles: (m, 3) integers, counter-clockwise seen
    from outside.
Mesh(mesh)  any object with .vertices and .faces (a trimesh.Trimesh).
Mesh.load(path, weld=False, allow_zero_area=False)  OBJ, OFF, PLY or STL.

A mesh rtcd cannot use raises MeshError naming the first offending vertex
or triangle; nothing is repaired silently. weld joins vertices at identical
positions (triangle soups). The array properties are read-only views into
the mesh (no copy; each keeps the mesh alive).)")
      .def(py::init([](py::handle vertices, py::handle triangles, bool weld, bool allow_zero_area) {
             return mesh_of(vertices, triangles, weld, allow_zero_area);
           }),
           py::arg("vertices"), py::arg("triangles"), py::kw_only(), py::arg("weld") = false,
           py::arg("allow_zero_area") = false)
      .def(py::init([](py::handle mesh, bool weld, bool allow_zero_area) {
             if (!py::hasattr(mesh, "vertices") || !py::hasattr(mesh, "faces"))
               throw py::type_error("mesh: expected an object with .vertices and .faces, or vertices and triangles");
             return mesh_of(mesh.attr("vertices"), mesh.attr("faces"), weld, allow_zero_area);
           }),
           py::arg("mesh"), py::kw_only(), py::arg("weld") = false, py::arg("allow_zero_area") = false)
      .def_static(
          "load",
          [](const std::filesystem::path& path, bool weld, bool allow_zero_area) {
            MeshOptions options;
            options.weld = weld;
            options.allow_zero_area = allow_zero_area;
            return wrap(Mesh::load(path, options));
          },
          py::arg("path"), py::arg("weld") = false, py::arg("allow_zero_area") = false,
          "Loads OBJ, OFF, PLY or STL; vertex and triangle ids are the file's.")
      .def_property_readonly(
          "vertices", [](py::object self) { return rows_view(self.cast<const PyMesh&>().mesh().positions(), self); },
          "(n, 3) float32, read-only view")
      .def_property_readonly(
          "triangles", [](py::object self) { return rows_view(self.cast<const PyMesh&>().mesh().triangles(), self); },
          "(m, 3) uint32, read-only view")
      .def_property_readonly(
          "vertex_normals",
          [](py::object self) { return rows_view(self.cast<const PyMesh&>().mesh().vertex_normals(), self); },
          "(n, 3) float32 unit, angle-weighted; read-only view")
      .def_property_readonly(
          "triangle_normals",
          [](py::object self) { return rows_view(self.cast<const PyMesh&>().mesh().triangle_normals(), self); },
          "(m, 3) float32 unit (zero for a kept zero-area triangle); read-only view")
      .def_property_readonly(
          "neighbors", [](py::object self) { return rows_view(self.cast<const PyMesh&>().mesh().neighbors(), self); },
          "(m, 3) int32: the triangle across edge e = 0 (v2, v0), 1 (v0, v1), 2 (v1, v2); -1 none. Read-only view")
      .def_property_readonly("bounds", [](const PyMesh& p) { return bounds_array(p.mesh().bounds()); },
                             "(2, 3): min and max corner")
      .def_property_readonly("radius", [](const PyMesh& p) { return p.mesh().radius(); },
                             "Largest distance of a vertex from the mesh's origin")
      .def_property_readonly("convex", [](const PyMesh& p) { return p.mesh().convex(); })
      .def_property_readonly("report",
                             [](const PyMesh& p) {
                               const MeshReport& r = p.mesh().report();
                               return py::dict(py::arg("boundary_edges") = r.boundary_edges,
                                               py::arg("zero_area_triangles") = r.zero_area_triangles,
                                               py::arg("unreferenced_vertices") = r.unreferenced_vertices);
                             })
      .def(
          "check",
          [](const PyMesh& p) {
            return to_python(app::to_json(check_mesh(p.mesh().positions(), p.mesh().triangles())));
          },
          "The checker's findings, as `rtcd check --json` prints them for one file.")
      .def(
          "save_obj", [](const PyMesh& p, const std::filesystem::path& path) { save_obj(p.mesh(), path); },
          py::arg("path"), "Writes a Wavefront OBJ that Mesh.load reads back to the same mesh.")
      .def("__len__", [](const PyMesh& p) { return p.mesh().triangle_count(); })
      .def("__repr__", [](const PyMesh& p) {
        return "<rtcd.Mesh " + std::to_string(p.mesh().vertex_count()) + " vertices, " +
               std::to_string(p.mesh().triangle_count()) + " triangles>";
      });

  m.def(
      "check_mesh",
      [](py::handle vertices, py::handle triangles) {
        const MeshData d = data_of(vertices, triangles);
        return to_python(app::to_json(check_mesh(d.positions, d.triangles)));
      },
      py::arg("vertices"), py::arg("triangles"),
      "The checker's findings on vertices and triangles as given (never raises on a defect).");
  m.def(
      "check_file",
      [](const std::filesystem::path& path, bool weld) {
        MeshData d = read_mesh_file(path);
        if (weld) weld_coincident(d.positions, d.triangles);
        return to_python(app::to_json(check_mesh(d.positions, d.triangles)));
      },
      py::arg("path"), py::arg("weld") = false, "The checker's findings on a mesh file, as `rtcd check --json`.");

  py::class_<Shape, std::shared_ptr<Shape>>(m, "Shape", R"(What a body is made of: a mesh, a sphere, a box or a half-space.

Shape(mesh) shares the mesh (a Mesh is accepted wherever a Shape is).
Shape.sphere(radius, sampling_density=0.0): rays from a level-2 icosphere's
162 vertices; Shape.box(half_extents, sampling_density=0.0): from the 8
corners (sampling_density > 0 adds origins per unit area);
Shape.half_space(): z <= 0 of its frame, a ground.)")
      .def(py::init([](const PyMesh& mesh) { return std::const_pointer_cast<Shape>(mesh.shape); }), py::arg("mesh"))
      .def_static(
          "sphere",
          [](double radius, double sampling_density) {
            return std::make_shared<Shape>(Sphere{radius}, sampling_density);
          },
          py::arg("radius"), py::arg("sampling_density") = 0.0)
      .def_static(
          "box",
          [](py::handle half_extents, double sampling_density) {
            const auto h = float_rows(half_extents, "half_extents", 3, true);
            if (h.ndim() != 1) throw UsageError("half_extents: expected 3 numbers");
            return std::make_shared<Shape>(Box{{h.at(0), h.at(1), h.at(2)}}, sampling_density);
          },
          py::arg("half_extents"), py::arg("sampling_density") = 0.0)
      .def_static("half_space", [] { return std::make_shared<Shape>(HalfSpace{}); })
      .def_property_readonly("kind", [](const Shape& s) { return kind_of(s); })
      .def_property_readonly("mesh",
                             [](const std::shared_ptr<Shape>& s) -> py::object {
                               if (!s->mesh()) return py::none();
                               return py::cast(PyMesh{s});
                             })
      .def_property_readonly("radius", &Shape::radius)
      .def_property_readonly("bounds", [](const Shape& s) { return bounds_array(s.bounds()); })
      .def_property_readonly(
          "origins",
          [](py::object self) { return rows_view(std::span<const Eigen::Vector3f>(self.cast<const Shape&>().sources().origins), self); },
          "(n, 3) float32: the ray origins in the shape's frame; read-only view")
      .def_property_readonly(
          "directions",
          [](py::object self) { return rows_view(std::span<const Eigen::Vector3f>(self.cast<const Shape&>().sources().directions), self); },
          "(n, 3) float32: each origin's inward unit direction; read-only view")
      .def_property_readonly(
          "edges",
          [](py::object self) {
            const auto& e = self.cast<const Shape&>().sources().edges;
            return view(reinterpret_cast<const uint32_t*>(e.data()), e.size(), 2, self);
          },
          "(e, 2) uint32: the edges between origins, lower id first; read-only view")
      .def("__repr__", [](const Shape& s) { return std::string("<rtcd.Shape ") + kind_of(s) + ">"; });

  py::module_ gen = m.def_submodule("gen", "Meshes generated in code: the validation families' and benchmarks' bodies.");
  gen.def(
      "box",
      [](py::handle half_extents) {
        const auto h = float_rows(half_extents, "half_extents", 3, true);
        if (h.ndim() != 1) throw UsageError("half_extents: expected 3 numbers");
        return wrap(gen::box({h.at(0), h.at(1), h.at(2)}));
      },
      py::arg("half_extents"));
  gen.def("icosphere", [](double r, int level) { return wrap(gen::icosphere(r, level)); }, py::arg("radius"),
          py::arg("level"));
  gen.def(
      "torus", [](double R, double r, int a, int b) { return wrap(gen::torus(R, r, a, b)); }, py::arg("major_radius"),
      py::arg("minor_radius"), py::arg("major_segments"), py::arg("minor_segments"));
  gen.def(
      "concave_blob", [](int triangles, uint32_t seed, double radius) { return wrap(gen::concave_blob(triangles, seed, radius)); },
      py::arg("triangles"), py::arg("seed"), py::arg("radius") = 1.0);
  gen.def(
      "open_sheet", [](int n, double size, double amplitude) { return wrap(gen::open_sheet(n, size, amplitude)); },
      py::arg("n"), py::arg("size"), py::arg("amplitude"));
  gen.def(
      "u_shape", [](double scale, double half_depth) { return wrap(gen::u_shape(scale, half_depth)); },
      py::arg("scale") = 1.0, py::arg("half_depth") = 0.5);
  gen.def("tetrahedron", [](double radius) { return wrap(gen::tetrahedron(radius)); }, py::arg("radius"));
  gen.def("octahedron", [](double radius) { return wrap(gen::octahedron(radius)); }, py::arg("radius"));
  gen.def(
      "torus_knot",
      [](int p, int q, double radius, double tube_radius, int segments, int sides) {
        return wrap(gen::torus_knot(p, q, radius, tube_radius, segments, sides));
      },
      py::arg("p"), py::arg("q"), py::arg("radius"), py::arg("tube_radius"), py::arg("segments"), py::arg("sides"));
  gen.def(
      "gear",
      [](int teeth, double root, double tip, double half_thickness) {
        return wrap(gen::gear(teeth, root, tip, half_thickness));
      },
      py::arg("teeth"), py::arg("root_radius"), py::arg("tip_radius"), py::arg("half_thickness"));
  gen.def("cactus", [](double height) { return wrap(gen::cactus(height)); }, py::arg("height"));
}

}  // namespace rtcd::python
