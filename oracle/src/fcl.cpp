// FCL 0.7 reference (double precision): meshes as BVHModel<OBBRSS> built once,
// spheres and boxes as FCL primitives; collide and distance at given poses.
#include <fcl/fcl.h>

#include <cmath>
#include <variant>

#include "overloaded.hpp"
#include "rtcd/oracle/third_party.hpp"

namespace rtcd::oracle {

namespace {

std::shared_ptr<fcl::CollisionGeometryd> make_geometry(const Shape& shape) {
  return std::visit(
      overloaded{
          [](const Mesh& mesh) -> std::shared_ptr<fcl::CollisionGeometryd> {
            std::vector<fcl::Vector3d> vertices;
            vertices.reserve(mesh.vertex_count());
            for (const Eigen::Vector3f& p : mesh.positions()) vertices.push_back(p.cast<double>());
            std::vector<fcl::Triangle> triangles;
            triangles.reserve(mesh.triangle_count());
            for (const Mesh::Triangle& t : mesh.triangles()) triangles.emplace_back(t[0], t[1], t[2]);
            auto model = std::make_shared<fcl::BVHModel<fcl::OBBRSSd>>();
            model->beginModel(static_cast<int>(triangles.size()), static_cast<int>(vertices.size()));
            model->addSubModel(vertices, triangles);
            model->endModel();
            model->computeLocalAABB();
            return model;
          },
          [](const Sphere& sphere) -> std::shared_ptr<fcl::CollisionGeometryd> {
            auto s = std::make_shared<fcl::Sphered>(sphere.radius);
            s->computeLocalAABB();
            return s;
          },
          [](const Box& box) -> std::shared_ptr<fcl::CollisionGeometryd> {
            // fcl::Box takes full side lengths, not half extents.
            auto b = std::make_shared<fcl::Boxd>(2.0 * box.half_extents);
            b->computeLocalAABB();
            return b;
          },
          [](const HalfSpace&) -> std::shared_ptr<fcl::CollisionGeometryd> {
            auto h = std::make_shared<fcl::Halfspaced>(Eigen::Vector3d::UnitZ(), 0.0);
            h->computeLocalAABB();
            return h;
          },
      },
      shape.geometry());
}

fcl::Transform3d to_fcl(const Pose& pose) {
  fcl::Transform3d tf = fcl::Transform3d::Identity();
  tf.linear() = pose.orientation.normalized().toRotationMatrix();
  tf.translation() = pose.position;
  return tf;
}

}  // namespace

struct FclShape::Impl {
  std::shared_ptr<fcl::CollisionGeometryd> geometry;
  bool mesh = false;
};

FclShape::FclShape(const Shape& shape)
    : impl_(std::make_unique<Impl>(Impl{make_geometry(shape), shape.mesh() != nullptr})) {}
FclShape::~FclShape() = default;
FclShape::FclShape(FclShape&&) noexcept = default;
FclShape& FclShape::operator=(FclShape&&) noexcept = default;

ReferenceCollision FclShape::collide(const Pose& pose, const FclShape& other, const Pose& other_pose, bool contacts,
                                     size_t max_contacts) const {
  fcl::CollisionRequestd request(contacts ? max_contacts : 1, contacts);
  fcl::CollisionResultd result;
  fcl::collide(impl_->geometry.get(), to_fcl(pose), other.impl_->geometry.get(), to_fcl(other_pose), request,
               result);

  ReferenceCollision out;
  out.colliding = result.isCollision();
  if (contacts) {
    // FCL documents its normal as pointing from o1 (A) to o2 (B), and that
    // holds for mesh-mesh, mesh-volume and volume-volume pairs. A volume
    // against a mesh (FCL 0.7 runs the mesh-volume test with the roles
    // swapped and keeps the triangle's normal) comes out B towards A already.
    // We report B towards A throughout; the tests pin each case.
    const bool b_to_a = !impl_->mesh && other.impl_->mesh;
    out.contacts.reserve(result.numContacts());
    for (size_t i = 0; i < result.numContacts(); ++i) {
      const fcl::Contactd& c = result.getContact(i);
      ReferenceContact rc;
      rc.position = c.pos;
      // Touching triangle pairs come without a normal; those stay zero.
      const double n = c.normal.norm();
      if (n > 0.0) rc.normal = (b_to_a ? c.normal : Eigen::Vector3d(-c.normal)) / n;
      // FCL 0.7's sphere-triangle test reports the depth negated, and
      // touching triangle pairs come as -0: the magnitude is the depth.
      rc.depth = std::abs(c.penetration_depth);
      out.contacts.push_back(rc);
    }
  }
  return out;
}

double FclShape::distance(const Pose& pose, const FclShape& other, const Pose& other_pose) const {
  fcl::DistanceRequestd request;
  fcl::DistanceResultd result;
  return fcl::distance(impl_->geometry.get(), to_fcl(pose), other.impl_->geometry.get(), to_fcl(other_pose),
                       request, result);
}

}  // namespace rtcd::oracle
