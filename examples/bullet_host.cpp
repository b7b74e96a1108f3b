// A host's own Bullet world using rtcd's narrow phase for its meshes: no
// scene file, just the batch dispatcher. A concave mesh falls on a ground
// plane; a Bullet sphere (no rtcd link) collides through Bullet's own
// algorithms in the same world. Exits 1 if the mesh does not come to rest on
// the ground.
#include <cstdio>
#include <memory>

#include <btBulletDynamicsCommon.h>

#include "rtcd/backend.hpp"
#include "rtcd/mesh.hpp"
#include "rtcd/narrow_phase.hpp"
#include "rtcd/sim/dispatcher.hpp"
#include "rtcd/sim/mass.hpp"

int main(int argc, char** argv) {
  const char* mesh_file = argc > 1 ? argv[1] : "data/meshes/u_shape.obj";

  // The narrow phase and the shapes it knows.
  auto narrow = rtcd::make_narrow_phase("auto");
  auto mesh = std::make_shared<rtcd::Shape>(rtcd::Mesh::load(mesh_file));
  auto ground = std::make_shared<rtcd::Shape>(rtcd::HalfSpace{});
  const rtcd::ShapeId mesh_shape = narrow->add_shape(mesh);
  const rtcd::ShapeId ground_shape = narrow->add_shape(ground);

  // Bullet's world, with the batch dispatcher in place of Bullet's own.
  btDefaultCollisionConfiguration configuration;
  rtcd::sim::BatchDispatcher dispatcher(&configuration, *narrow);
  btDbvtBroadphase broadphase;
  btSequentialImpulseConstraintSolver solver;
  btDiscreteDynamicsWorld world(&dispatcher, &broadphase, &solver, &configuration);
  world.setGravity(btVector3(0, 0, -9.81f));

  // The ground: a Bullet plane for the broad phase, a half-space for rtcd.
  btStaticPlaneShape plane(btVector3(0, 0, 1), 0);
  btRigidBody floor(btRigidBody::btRigidBodyConstructionInfo(0, nullptr, &plane));
  world.addRigidBody(&floor);
  dispatcher.link(&floor, {narrow->add_body(ground_shape, {}), rtcd::Pose{}, 0.6, 0.0});

  // The mesh: mass and inertia from its volume integrals; Bullet simulates
  // its principal frame, so the link says where the mesh sits in it.
  const rtcd::sim::MassProperties mass = rtcd::sim::mass_properties(*mesh, 500.0);
  const rtcd::Pose principal = mass.principal_frame();
  // The broad phase's box: every vertex is within this reach of the centre
  // of mass, whatever the rotation.
  const btScalar reach = btScalar(mesh->radius() + mass.centre_of_mass.norm());
  btBoxShape bounds(btVector3(reach, reach, reach));
  const btVector3 inertia(btScalar(mass.principal_moments.x()), btScalar(mass.principal_moments.y()),
                          btScalar(mass.principal_moments.z()));
  btRigidBody::btRigidBodyConstructionInfo info(btScalar(mass.mass), nullptr, &bounds, inertia);
  const rtcd::Pose start{{0, 0, 2}, Eigen::Quaterniond(Eigen::AngleAxisd(0.3, Eigen::Vector3d::UnitX()))};
  const rtcd::Pose body_pose = start * principal;
  const Eigen::Quaterniond& q = body_pose.orientation;
  info.m_startWorldTransform = btTransform(btQuaternion(btScalar(q.x()), btScalar(q.y()), btScalar(q.z()), btScalar(q.w())),
                                           btVector3(btScalar(body_pose.position.x()), btScalar(body_pose.position.y()),
                                                     btScalar(body_pose.position.z())));
  btRigidBody body(info);
  body.setActivationState(DISABLE_DEACTIVATION);
  world.addRigidBody(&body);
  dispatcher.link(&body, {narrow->add_body(mesh_shape, start), principal.inverse(), 0.6, 0.0});

  // A Bullet sphere elsewhere: its pair with the floor is Bullet's business.
  btSphereShape ball_shape(0.3f);
  btRigidBody::btRigidBodyConstructionInfo ball_info(1, nullptr, &ball_shape, btVector3(0.036f, 0.036f, 0.036f));
  ball_info.m_startWorldTransform.setOrigin(btVector3(5, 0, 1));
  btRigidBody ball(ball_info);
  world.addRigidBody(&ball);

  for (int step = 0; step < 240; ++step) world.stepSimulation(1.0f / 60, 0, 1.0f / 60);

  const rtcd::Pose rest = dispatcher.shape_pose(&body);
  std::printf("mesh at rest: centre z %.4f, speed %.4f m/s; last batch %zu pairs, %zu solver points; ball z %.3f\n",
              rest.position.z(), double(body.getLinearVelocity().length()), dispatcher.last_batch().pairs,
              dispatcher.last_batch().points, double(ball.getWorldTransform().getOrigin().z()));
  world.removeRigidBody(&ball);
  dispatcher.unlink(&body);
  world.removeRigidBody(&body);
  dispatcher.unlink(&floor);
  world.removeRigidBody(&floor);
  const bool resting = rest.position.z() > 0 && rest.position.z() < 2 && body.getLinearVelocity().length() < 0.05f;
  const bool ball_on_floor = ball.getWorldTransform().getOrigin().z() > 0.25f;
  return resting && ball_on_floor ? 0 : 1;
}
