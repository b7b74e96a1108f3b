// rtcd.oracle: the references the differential tests judge rtcd by, bound
// so a test suite can write its own: the exact reference, FCL, GIMPACT and
// libccd, on the same shapes and poses.
#include "module.hpp"
#include "rtcd/error.hpp"
#include "rtcd/oracle/exact.hpp"
#include "rtcd/oracle/third_party.hpp"

namespace rtcd::python {
namespace {

using oracle::ExactShape;
using oracle::FclShape;
using oracle::GimpactShape;
using oracle::ReferenceCollision;

// Points (n, 3) mapped through f(point) into an array of R.
template <class R, class F>
py::array_t<R> per_point(py::handle points, const char* name, F&& f) {
  const auto p = float_rows(points, name, 3);
  py::array_t<R> out(p.shape(0));
  for (py::ssize_t i = 0; i < p.shape(0); ++i) out.mutable_at(i) = f(Eigen::Vector3d(p.at(i, 0), p.at(i, 1), p.at(i, 2)));
  return out;
}

py::dict collision(const ReferenceCollision& c) {
  const size_t n = c.contacts.size();
  py::array_t<double> position({py::ssize_t(n), py::ssize_t(3)}), normal({py::ssize_t(n), py::ssize_t(3)});
  py::array_t<double> depth{py::ssize_t(n)};
  for (size_t i = 0; i < n; ++i) {
    for (int k = 0; k < 3; ++k) {
      position.mutable_at(i, k) = c.contacts[i].position[k];
      normal.mutable_at(i, k) = c.contacts[i].normal[k];
    }
    depth.mutable_at(i) = c.contacts[i].depth;
  }
  return py::dict(py::arg("colliding") = c.colliding, py::arg("position") = position, py::arg("normal") = normal,
                  py::arg("depth") = depth);
}

}  // namespace

void bind_oracles(py::module_& m) {
  py::module_ o = m.def_submodule("oracle", R"(The references rtcd is judged by, on the same shapes and poses:
Exact (double precision, brute force), Fcl, Gimpact (Bullet), and
ccd_penetration (libccd, convex shapes). Poses are [tx, ty, tz, qw, qx, qy, qz].)");

  py::class_<ExactShape>(o, "Exact", R"(The exact reference over one shape, in double precision.

inside, distance and first_hit answer in the shape's own frame;
rays_from(source, source_pose, pose, margin) judges every ray origin of
`source` against this shape: dict of arrays near, inside, near_surface,
deep (inside beyond the margin), depth (the inward ray's first hit; -1
outside), penetration (the distance to the nearest surface, the true
depth; -1 outside) and triangle.)")
      .def(py::init([](py::handle shape) { return std::make_unique<ExactShape>(shape_of(shape, "shape")); }),
           py::arg("shape"))
      .def_property_readonly("closed", &ExactShape::closed)
      .def(
          "inside",
          [](const ExactShape& e, py::handle points) {
            return per_point<bool>(points, "points", [&](const Eigen::Vector3d& p) { return e.inside(p); });
          },
          py::arg("points"))
      .def(
          "distance",
          [](const ExactShape& e, py::handle points) {
            return per_point<double>(points, "points", [&](const Eigen::Vector3d& p) { return e.distance(p); });
          },
          py::arg("points"))
      .def(
          "closest_point",
          [](const ExactShape& e, py::handle points) {
            const auto p = float_rows(points, "points", 3);
            py::array_t<double> out({p.shape(0), py::ssize_t(3)});
            for (py::ssize_t i = 0; i < p.shape(0); ++i) {
              const Eigen::Vector3d q = e.closest_point({p.at(i, 0), p.at(i, 1), p.at(i, 2)});
              for (int k = 0; k < 3; ++k) out.mutable_at(i, k) = q[k];
            }
            return out;
          },
          py::arg("points"), "(n, 3): each point's nearest point of the surface")
      .def(
          "first_hit",
          [](const ExactShape& e, py::handle origins, py::handle directions) {
            const auto o = float_rows(origins, "origins", 3), d = float_rows(directions, "directions", 3);
            if (o.shape(0) != d.shape(0))
              throw UsageError("first_hit: " + std::to_string(o.shape(0)) + " origins but " +
                               std::to_string(d.shape(0)) + " directions");
            py::array_t<double> t(o.shape(0));
            py::array_t<int32_t> triangle(o.shape(0));
            for (py::ssize_t i = 0; i < o.shape(0); ++i) {
              double hit = 0;
              int32_t face = -1;
              const bool found = e.first_hit({o.at(i, 0), o.at(i, 1), o.at(i, 2)}, {d.at(i, 0), d.at(i, 1), d.at(i, 2)}, hit, face);
              t.mutable_at(i) = found ? hit : std::numeric_limits<double>::infinity();
              triangle.mutable_at(i) = found ? face : -1;
            }
            return py::make_tuple(t, triangle);
          },
          py::arg("origins"), py::arg("directions"), "(t, triangle) of each ray's nearest hit; inf and -1 where none.")
      .def(
          "rays_from",
          [](const ExactShape& e, py::handle source, py::handle source_pose, py::handle pose, double margin) {
            const auto s = shape_of(source, "source");
            const Pose sp = pose_of(source_pose, "source_pose"), p = pose_of(pose, "pose");
            std::vector<oracle::ExactRay> rays;
            {
              py::gil_scoped_release release;
              rays = e.rays_from(*s, sp, p, margin);
            }
            const py::ssize_t n = py::ssize_t(rays.size());
            py::array_t<bool> near(n), inside(n), near_surface(n), deep(n);
            py::array_t<double> depth(n), penetration(n);
            py::array_t<int32_t> triangle(n);
            for (py::ssize_t i = 0; i < n; ++i) {
              const auto& r = rays[size_t(i)];
              near.mutable_at(i) = r.near;
              inside.mutable_at(i) = r.inside;
              near_surface.mutable_at(i) = r.near_surface;
              deep.mutable_at(i) = r.deep();
              depth.mutable_at(i) = r.depth;
              penetration.mutable_at(i) = r.penetration;
              triangle.mutable_at(i) = r.triangle;
            }
            return py::dict(py::arg("near") = near, py::arg("inside") = inside, py::arg("near_surface") = near_surface,
                            py::arg("deep") = deep, py::arg("depth") = depth, py::arg("penetration") = penetration,
                            py::arg("triangle") = triangle);
          },
          py::arg("source"), py::arg("source_pose"), py::arg("pose"), py::arg("margin"))
      .def(
          "edge_depths",
          [](const ExactShape& e, py::handle source, py::handle source_pose, py::handle pose) {
            const auto s = shape_of(source, "source");
            const Pose sp = pose_of(source_pose, "source_pose"), p = pose_of(pose, "pose");
            std::vector<double> d;
            {
              py::gil_scoped_release release;
              d = e.edge_depths(*s, sp, p);
            }
            return py::array_t<double>(py::ssize_t(d.size()), d.data());
          },
          py::arg("source"), py::arg("source_pose"), py::arg("pose"),
          "Per edge of source (Shape.edges): how deep its crossing of this shape is, -1 where an end is inside or it "
          "does not cross.");

  // FCL and GIMPACT keep the Shape they were made of alive beside their own copy.
  struct Fcl {
    std::shared_ptr<const Shape> shape;
    FclShape fcl;
  };
  py::class_<Fcl>(o, "Fcl", "FCL 0.7: meshes as BVHModel<OBBRSS>, spheres and boxes as FCL primitives.")
      .def(py::init([](py::handle shape) {
             auto s = shape_of(shape, "shape");
             return std::make_unique<Fcl>(Fcl{s, FclShape(*s)});
           }),
           py::arg("shape"))
      .def(
          "collide",
          [](const Fcl& f, py::handle pose, const Fcl& other, py::handle other_pose, bool contacts,
             size_t max_contacts) {
            const Pose p = pose_of(pose, "pose"), q = pose_of(other_pose, "other_pose");
            ReferenceCollision c;
            {
              py::gil_scoped_release release;
              c = f.fcl.collide(p, other.fcl, q, contacts, max_contacts);
            }
            return collision(c);
          },
          py::arg("pose"), py::arg("other"), py::arg("other_pose"), py::arg("contacts") = false,
          py::arg("max_contacts") = 1000, "colliding, and with contacts=True FCL's contact points.")
      .def(
          "distance",
          [](const Fcl& f, py::handle pose, const Fcl& other, py::handle other_pose) {
            const Pose p = pose_of(pose, "pose"), q = pose_of(other_pose, "other_pose");
            py::gil_scoped_release release;
            return f.fcl.distance(p, other.fcl, q);
          },
          py::arg("pose"), py::arg("other"), py::arg("other_pose"), "Minimum distance (0 or below when touching).");

  struct Gimpact {
    std::shared_ptr<const Shape> shape;
    GimpactShape gimpact;
  };
  py::class_<Gimpact>(o, "Gimpact", "Bullet's GIMPACT: meshes as btGImpactMeshShape; penetrating points only.")
      .def(py::init([](py::handle shape) {
             auto s = shape_of(shape, "shape");
             return std::make_unique<Gimpact>(Gimpact{s, GimpactShape(*s)});
           }),
           py::arg("shape"))
      .def(
          "collide",
          [](const Gimpact& g, py::handle pose, const Gimpact& other, py::handle other_pose) {
            const Pose p = pose_of(pose, "pose"), q = pose_of(other_pose, "other_pose");
            ReferenceCollision c;
            {
              py::gil_scoped_release release;
              c = g.gimpact.collide(p, other.gimpact, q);
            }
            return collision(c);
          },
          py::arg("pose"), py::arg("other"), py::arg("other_pose"));

  o.def(
      "ccd_penetration",
      [](py::handle a, py::handle pose_a, py::handle b, py::handle pose_b) {
        const auto sa = shape_of(a, "a"), sb = shape_of(b, "b");
        const Pose pa = pose_of(pose_a, "pose_a"), pb = pose_of(pose_b, "pose_b");
        const oracle::ConvexPenetration c = oracle::ccd_penetration(*sa, pa, *sb, pb);
        return py::dict(py::arg("colliding") = c.colliding, py::arg("depth") = c.depth,
                        py::arg("direction") = py::array_t<double>(3, c.direction.data()),
                        py::arg("position") = py::array_t<double>(3, c.position.data()));
      },
      py::arg("a"), py::arg("pose_a"), py::arg("b"), py::arg("pose_b"),
      "libccd's GJK/EPA on convex shapes (a mesh as the hull of its vertices): colliding, depth, direction (move b "
      "by depth * direction to separate), position.");
}

}  // namespace rtcd::python
