// Bullet GIMPACT reference: meshes as btGImpactMeshShape, spheres and boxes as
// Bullet convex shapes, collided through a dispatcher with the GImpact
// algorithm registered; every penetrating point the algorithm emits is kept.
#include <btBulletCollisionCommon.h>
#include <BulletCollision/Gimpact/btGImpactCollisionAlgorithm.h>
#include <BulletCollision/Gimpact/btGImpactShape.h>

#include <variant>

#include "overloaded.hpp"
#include "rtcd/oracle/third_party.hpp"

namespace rtcd::oracle {

namespace {

// One dispatcher per thread, made on first use: building the configuration
// allocates its pools, far too costly per query. Sequential queries on
// different shapes share it safely; every algorithm is freed after its call.
struct Dispatch {
  btDefaultCollisionConfiguration configuration;
  btCollisionDispatcher dispatcher{&configuration};
  btDispatcherInfo info;
  Dispatch() { btGImpactCollisionAlgorithm::registerAlgorithm(&dispatcher); }
};

Dispatch& dispatch() {
  thread_local Dispatch d;
  return d;
}

btTransform to_bullet(const Pose& pose) {
  const Eigen::Quaterniond q = pose.orientation.normalized();
  return btTransform(btQuaternion(btScalar(q.x()), btScalar(q.y()), btScalar(q.z()), btScalar(q.w())),
                     btVector3(btScalar(pose.position.x()), btScalar(pose.position.y()), btScalar(pose.position.z())));
}

Eigen::Vector3d to_eigen(const btVector3& v) { return {v.x(), v.y(), v.z()}; }

// Takes every point straight from the algorithm instead of going through a
// persistent manifold, which would keep at most 4 and merge near ones.
// Bullet gives the normal on the manifold's second body, pointing towards its
// first, and the point on that second body. The GImpact algorithm swaps the
// bodies internally for a volume against a mesh but builds its manifold in
// our order again (never seen swapped in the tests); were it swapped, the
// normal and point are brought back to our A/B order here.
class CollectingResult : public btManifoldResult {
 public:
  CollectingResult(const btCollisionObjectWrapper* a, const btCollisionObjectWrapper* b, ReferenceCollision& out)
      : btManifoldResult(a, b), object_a_(a->getCollisionObject()), out_(out) {}

  void addContactPoint(const btVector3& normal_on_b, const btVector3& point_on_b, btScalar distance) override {
    if (!(distance < 0)) return;  // touching or within the margin only
    const bool swapped = m_manifoldPtr != nullptr && m_manifoldPtr->getBody0() != object_a_;
    ReferenceContact c;
    c.depth = -double(distance);
    const Eigen::Vector3d n = to_eigen(normal_on_b);
    const Eigen::Vector3d p = to_eigen(point_on_b);
    // Not swapped: Bullet's B is ours and its normal already points B -> A.
    // Swapped: Bullet's B is our A; its point on our B is p + n * distance.
    c.normal = swapped ? Eigen::Vector3d(-n) : n;
    c.position = swapped ? Eigen::Vector3d(p + n * double(distance)) : p;
    const double len = c.normal.norm();
    if (len > 0.0) c.normal /= len;
    out_.contacts.push_back(c);
  }

 private:
  const btCollisionObject* object_a_;
  ReferenceCollision& out_;
};

}  // namespace

struct GimpactShape::Impl {
  // The vertex and index arrays the Bullet mesh interface points into.
  std::vector<btScalar> vertices;
  std::vector<int> indices;
  std::unique_ptr<btTriangleIndexVertexArray> mesh_interface;
  std::unique_ptr<btCollisionShape> shape;
};

GimpactShape::GimpactShape(const Shape& shape) : impl_(std::make_unique<Impl>()) {
  Impl& impl = *impl_;
  std::visit(overloaded{
                 [&](const Mesh& mesh) {
                   impl.vertices.reserve(3 * mesh.vertex_count());
                   for (const Eigen::Vector3f& p : mesh.positions())
                     impl.vertices.insert(impl.vertices.end(), {p.x(), p.y(), p.z()});
                   impl.indices.reserve(3 * mesh.triangle_count());
                   for (const Mesh::Triangle& t : mesh.triangles())
                     impl.indices.insert(impl.indices.end(), {int(t[0]), int(t[1]), int(t[2])});
                   impl.mesh_interface = std::make_unique<btTriangleIndexVertexArray>(
                       int(mesh.triangle_count()), impl.indices.data(), int(3 * sizeof(int)), int(mesh.vertex_count()),
                       impl.vertices.data(), int(3 * sizeof(btScalar)));
                   auto gimpact = std::make_unique<btGImpactMeshShape>(impl.mesh_interface.get());
                   // Margin 0: GIMPACT's triangle-triangle clipping counts
                   // points within the summed margins as penetrating and adds
                   // the margins to the depth, so any margin would report
                   // separated meshes as colliding and inflate every depth.
                   gimpact->setMargin(0);
                   gimpact->updateBound();
                   impl.shape = std::move(gimpact);
                 },
                 [&](const Sphere& sphere) {
                   // A sphere's margin is its radius (a point core), exact.
                   impl.shape = std::make_unique<btSphereShape>(btScalar(sphere.radius));
                 },
                 [&](const Box& box) {
                   const Eigen::Vector3d h = box.half_extents;
                   auto b = std::make_unique<btBoxShape>(btVector3(btScalar(h.x()), btScalar(h.y()), btScalar(h.z())));
                   // The box keeps its outer size whatever the margin; the
                   // margin only rounds its edges. 1e-4 of the smallest half
                   // extent keeps that rounding negligible while GJK still
                   // has a non-degenerate margin to work with.
                   b->setMargin(btScalar(1e-4 * h.minCoeff()));
                   impl.shape = std::move(b);
                 },
                 [&](const HalfSpace&) {
                   impl.shape = std::make_unique<btStaticPlaneShape>(btVector3(0, 0, 1), btScalar(0));
                 },
             },
             shape.geometry());
}

GimpactShape::~GimpactShape() = default;
GimpactShape::GimpactShape(GimpactShape&&) noexcept = default;
GimpactShape& GimpactShape::operator=(GimpactShape&&) noexcept = default;

ReferenceCollision GimpactShape::collide(const Pose& pose, const GimpactShape& other, const Pose& other_pose) const {
  // Collision objects are made per call so that a shape may be collided with
  // itself and no state is kept between calls.
  btCollisionObject object_a;
  object_a.setCollisionShape(impl_->shape.get());
  object_a.setWorldTransform(to_bullet(pose));
  btCollisionObject object_b;
  object_b.setCollisionShape(other.impl_->shape.get());
  object_b.setWorldTransform(to_bullet(other_pose));

  const btCollisionObjectWrapper wrap_a(nullptr, object_a.getCollisionShape(), &object_a,
                                        object_a.getWorldTransform(), -1, -1);
  const btCollisionObjectWrapper wrap_b(nullptr, object_b.getCollisionShape(), &object_b,
                                        object_b.getWorldTransform(), -1, -1);

  ReferenceCollision out;
  Dispatch& d = dispatch();
  btCollisionAlgorithm* algorithm = d.dispatcher.findAlgorithm(&wrap_a, &wrap_b, nullptr, BT_CONTACT_POINT_ALGORITHMS);
  if (algorithm == nullptr) return out;
  CollectingResult result(&wrap_a, &wrap_b, out);
  algorithm->processCollision(&wrap_a, &wrap_b, d.info, &result);
  algorithm->~btCollisionAlgorithm();
  d.dispatcher.freeCollisionAlgorithm(algorithm);
  out.colliding = !out.contacts.empty();
  return out;
}

}  // namespace rtcd::oracle
