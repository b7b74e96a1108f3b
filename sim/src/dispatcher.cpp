// The batch dispatcher. Bullet's manifolds were made for per-pair algorithms
// that refresh a few points each step; writing them from a batch has traps,
// each handled here (docs/ARCHITECTURE.md, "Simulation"):
// - four points per manifold: a pair gets as many manifolds as its chosen
//   points need, so no point is dropped by Bullet's own reduction;
// - the breaking threshold: the solver skips points farther apart than a
//   manifold's processing threshold, and refreshContactPoints drops them past
//   the breaking one; both are set to the distance extension (unlimited where
//   it is derived per pair), and the points
//   are never refreshed by Bullet (they are rewritten every step);
// - hand-written points carry no combined friction or restitution: set here
//   from the linked bodies (products, as Bullet combines them);
// - rewriting points loses warm starting: each new point takes the impulses
//   of last step's point from the same ray (source body and vertex);
// - a pair the broad phase dropped keeps its manifolds until released: any
//   pair not seen in a batch has them released.
#include "rtcd/sim/dispatcher.hpp"

#include <algorithm>
#include <limits>
#include <utility>

#include <BulletDynamics/Dynamics/btRigidBody.h>

#include "bullet_math.hpp"
#include "rtcd/error.hpp"

namespace rtcd::sim {
namespace {


}  // namespace

BatchDispatcher::BatchDispatcher(btCollisionConfiguration* configuration, NarrowPhase& narrow, DispatcherOptions options)
    : btCollisionDispatcher(configuration), narrow_(narrow), options_(options) {
  if (options_.points_per_pair < 1 || options_.points_per_pair > 64)
    throw ConfigError("points_per_pair is " + std::to_string(options_.points_per_pair) + ", must be in [1, 64]");
}

BatchDispatcher::~BatchDispatcher() {
  for (auto& [key, held] : held_) release(held);
}

void BatchDispatcher::link(btCollisionObject* object, const BodyLink& link) {
  if (!object) throw UsageError("link: null collision object");
  if (slot_of(object)) throw UsageError("link: the object is linked already");
  object->setUserIndex3(int(slots_.size()));
  slots_.push_back({object, link});
}

void BatchDispatcher::unlink(btCollisionObject* object) {
  const Slot* slot = slot_of(object);
  if (!slot) throw UsageError("unlink: the object is not linked");
  const BodyId id = slot->link.id;
  for (auto it = held_.begin(); it != held_.end();) {
    if (const BodyPair p = pair_of_key(it->first); p.a == id || p.b == id) {
      release(it->second);
      it = held_.erase(it);
    } else {
      ++it;
    }
  }
  slots_[object->getUserIndex3()].object = nullptr;
  object->setUserIndex3(-1);
}

const BatchDispatcher::Slot* BatchDispatcher::slot_of(const btCollisionObject* object) const {
  const int i = object->getUserIndex3();
  if (i < 0 || size_t(i) >= slots_.size() || slots_[i].object != object) return nullptr;
  return &slots_[i];
}

BatchDispatcher::Slot* BatchDispatcher::slot_of(const btCollisionObject* object) {
  return const_cast<Slot*>(std::as_const(*this).slot_of(object));
}

// The deepest (or, for gaps, the nearest) first, then each next the one
// farthest from those chosen. Deterministic: ties go to the earlier index.
void BatchDispatcher::choose_spread(std::span<const Candidate> c, size_t offset, size_t budget,
                                    std::vector<size_t>& chosen) {
  if (c.empty() || budget == 0) return;
  size_t first = 0;
  for (size_t i = 1; i < c.size(); ++i)
    if (c[i].distance < c[first].distance) first = i;
  spread_.assign(c.size(), std::numeric_limits<double>::infinity());  // squared distance to the chosen set
  for (size_t pick = first, count = 1;; ++count) {
    chosen.push_back(offset + pick);
    spread_[pick] = -1.0;
    if (count == std::min(budget, c.size())) break;
    size_t far = 0;
    double best = -1.0;
    for (size_t i = 0; i < c.size(); ++i) {
      if (spread_[i] < 0) continue;
      spread_[i] = std::min(spread_[i], (c[i].on_a - c[pick].on_a).squaredNorm());
      if (spread_[i] > best) best = spread_[i], far = i;
    }
    pick = far;
  }
}

// A speculative point acts only where the bodies would close its gap within
// the step: spread over every predictive ray, the points went mostly to gaps
// far from where the bodies met, and thin tubes fell into each other past
// their middles.
size_t BatchDispatcher::closing_first(const btCollisionObject* a, const btCollisionObject* b) {
  const btRigidBody* ra = btRigidBody::upcast(a);
  const btRigidBody* rb = btRigidBody::upcast(b);
  const auto velocity = [](const btRigidBody* r, const Eigen::Vector3d& at) {
    return r ? r->getVelocityInLocalPoint(bt(at) - r->getCenterOfMassPosition()) : btVector3(0, 0, 0);
  };
  const auto closes = [&](const Candidate& g) {
    const btVector3 relative = velocity(ra, g.on_a) - velocity(rb, g.on_b);
    return -double(relative.dot(bt(g.normal_on_b))) * step_seconds_ >= g.distance;
  };
  // A stable partition through kept scratch (std::stable_partition allocates).
  others_.clear();
  size_t closing = 0;
  for (const Candidate& g : gaps_) {
    if (closes(g))
      gaps_[closing++] = g;
    else
      others_.push_back(g);
  }
  std::copy(others_.begin(), others_.end(), gaps_.begin() + ptrdiff_t(closing));
  return closing;
}

Pose BatchDispatcher::shape_pose(const btCollisionObject* object) const {
  const Slot* slot = slot_of(object);
  if (!slot) throw UsageError("shape_pose: the object is not linked");
  return pose_of(object->getWorldTransform()) * slot->link.shape_in_body;
}

void BatchDispatcher::dispatchAllCollisionPairs(btOverlappingPairCache* pairs, const btDispatcherInfo& info,
                                                btDispatcher*) {
  auto t0 = Clock::now();
  batch_ = {batch_.calls + 1};
  step_seconds_ = info.m_timeStep;
  batch_pairs_.clear();
  batch_objects_.clear();
  btBroadphasePairArray& array = pairs->getOverlappingPairArray();
  for (int i = 0; i < pairs->getNumOverlappingPairs(); ++i) {
    btBroadphasePair& p = array[i];
    auto* o0 = static_cast<btCollisionObject*>(p.m_pProxy0->m_clientObject);
    auto* o1 = static_cast<btCollisionObject*>(p.m_pProxy1->m_clientObject);
    const Slot* s0 = slot_of(o0);
    const Slot* s1 = slot_of(o1);
    if (!s0 || !s1) {
      getNearCallback()(p, *this, info);  // Bullet's own algorithm for this pair
      continue;
    }
    if (!needsCollision(o0, o1)) {
      // Both asleep (or filtered): their manifolds stay as they were.
      if (auto it = held_.find(pair_key(s0->link.id, s1->link.id)); it != held_.end()) it->second.seen = batch_.calls;
      continue;
    }
    batch_pairs_.push_back({s0->link.id, s1->link.id});
    batch_objects_.push_back({o0, o1});
  }
  for (const auto& [o0, o1] : batch_objects_) {
    for (btCollisionObject* o : {o0, o1}) {
      Slot& slot = *slot_of(o);
      if (slot.posed == batch_.calls) continue;  // a body in many pairs is posed once
      slot.posed = batch_.calls;
      narrow_.set_pose(slot.link.id, shape_pose(o));
    }
  }
  auto t1 = Clock::now();
  narrow_.detect(batch_pairs_, result_);
  batch_.seconds_narrow = seconds_since(t1);
  batch_.pairs = batch_pairs_.size();

  for (size_t i = 0; i < batch_pairs_.size(); ++i) {
    PairManifolds& held = held_[pair_key(batch_pairs_[i].a, batch_pairs_[i].b)];
    held.seen = batch_.calls;
    fill(result_.pairs[i], batch_objects_[i].first, batch_objects_[i].second, held);
  }
  for (auto it = held_.begin(); it != held_.end();) {
    if (it->second.seen != batch_.calls) {
      release(it->second);
      it = held_.erase(it);
    } else {
      ++it;
    }
  }
  batch_.seconds_manifolds = seconds_since(t0) - batch_.seconds_narrow;
}

// The way a moves out of b: the pair's pushes summed (b's turned), unit; zero without any.
Eigen::Vector3d BatchDispatcher::way_out(const PairResult& pair) const {
  Eigen::Vector3d sum = Eigen::Vector3d::Zero();
  for (const Contact& c : result_.contacts_of(pair)) sum += c.source == Side::a ? c.push : Eigen::Vector3d(-c.push);
  const double n = sum.norm();
  return n > 0 ? Eigen::Vector3d(sum / n) : Eigen::Vector3d::Zero();
}

void BatchDispatcher::fill(const PairResult& pair, btCollisionObject* a, btCollisionObject* b, PairManifolds& held) {
  touching_.clear();
  gaps_.clear();
  // Shallow, the pair learns the way its bodies met; deeper, pushes against it turn.
  Eigen::Vector3d entry = Eigen::Vector3d::Zero();
  if (options_.keep_entry_direction) {
    const Eigen::Matrix3d b_frame = shape_pose(b).orientation.toRotationMatrix();
    const double thinner = std::min(slot_of(a)->link.thickness, slot_of(b)->link.thickness);
    if (pair.max_depth <= 0.25 * thinner) {
      if (const Eigen::Vector3d way = way_out(pair); way.squaredNorm() > 0) held.entry_in_b = b_frame.transpose() * way;
    } else {
      entry = b_frame * held.entry_in_b;
    }
  }
  for (const Contact& c : result_.contacts_of(pair)) {
    const double depth = c.push.norm();
    if (!(depth > 0)) continue;
    Eigen::Vector3d out = c.push / depth;  // moves the source vertex out of the target
    const Eigen::Vector3d way = c.source == Side::a ? entry : Eigen::Vector3d(-entry);
    if (out.dot(way) < 0) {
      out = way;
      ++batch_.entry_pushes;
    }
    const int i0 = c.kind == ContactKind::sphere ? -2 : int(c.edge[0]);
    const int i1 = c.kind == ContactKind::vertex ? -1 : c.kind == ContactKind::edge ? int(c.edge[1]) : -2;
    if (c.source == Side::a)
      touching_.push_back({c.origin, c.origin + depth * out, out, -depth, 0, i0, i1});
    else
      touching_.push_back({c.origin + depth * out, c.origin, -out, -depth, 1, i0, i1});
  }
  if (options_.speculative) {
    for (const PredictiveRay& r : result_.predictive_of(pair)) {
      // The gap along the contact normal, not along the ray: how far the
      // vertex is from the impacted triangle's plane.
      const double gap = r.distance * std::abs(r.direction.dot(r.normal));
      const Eigen::Vector3d on_target = r.origin - gap * r.normal;
      if (r.source == Side::a)
        gaps_.push_back({r.origin, on_target, r.normal, gap, 0, int(r.vertex), -1});
      else
        gaps_.push_back({on_target, r.origin, -r.normal, gap, 1, int(r.vertex), -1});
    }
  }
  // The touching points first; what they leave goes to the gaps that close
  // within the step, then to the others.
  const size_t points = options_.points_per_pair;
  chosen_touching_.clear();
  chosen_gaps_.clear();
  choose_spread(touching_, 0, points, chosen_touching_);
  const size_t closing = chosen_touching_.size() < points ? closing_first(a, b) : 0;
  const std::span<const Candidate> gaps(gaps_);
  choose_spread(gaps.first(closing), 0, points - chosen_touching_.size(), chosen_gaps_);
  choose_spread(gaps.subspan(closing), closing, points - chosen_touching_.size() - chosen_gaps_.size(), chosen_gaps_);

  // Last step's points, for warm starting, keyed by their ray.
  previous_.clear();
  for (btPersistentManifold* m : held.manifolds)
    for (int i = 0; i < m->getNumContacts(); ++i) previous_.push_back(m->getContactPoint(i));

  const size_t count = chosen_touching_.size() + chosen_gaps_.size();
  const size_t needed = (count + MANIFOLD_CACHE_SIZE - 1) / MANIFOLD_CACHE_SIZE;
  while (held.manifolds.size() > needed) {
    releaseManifold(held.manifolds.back());
    held.manifolds.pop_back();
  }
  while (held.manifolds.size() < needed) held.manifolds.push_back(getNewManifold(a, b));
  // Points lie within the pair's distance extension; a derived one differs
  // per pair, and every point written is meant for the solver.
  const double extension = narrow_.config().distance_extension.value_or(BT_LARGE_FLOAT);
  for (btPersistentManifold* m : held.manifolds) {
    m->clearManifold();
    m->setBodies(a, b);
    m->setContactBreakingThreshold(btScalar(extension));
    m->setContactProcessingThreshold(btScalar(extension));
  }

  const BodyLink& la = slot_of(a)->link;
  const BodyLink& lb = slot_of(b)->link;
  const btScalar friction = options_.friction ? btScalar(la.friction * lb.friction) : btScalar(0);
  const btScalar restitution = options_.restitution ? btScalar(la.restitution * lb.restitution) : btScalar(0);
  size_t written = 0;
  const auto write = [&](const Candidate& c) {
    const btVector3 pa = bt(c.on_a), pb = bt(c.on_b);
    btManifoldPoint pt(a->getWorldTransform().invXform(pa), b->getWorldTransform().invXform(pb), bt(c.normal_on_b),
                       btScalar(c.distance));
    pt.m_positionWorldOnA = pa;
    pt.m_positionWorldOnB = pb;
    pt.m_combinedFriction = friction;
    // A speculative point has not touched: it must not bounce.
    pt.m_combinedRestitution = c.distance < 0 ? restitution : btScalar(0);
    batch_.friction_points += pt.m_combinedFriction > 0;
    batch_.restitution_points += pt.m_combinedRestitution > 0;
    batch_.speculative_points += c.distance > 0;
    pt.m_partId0 = c.side;
    pt.m_index0 = c.index0;
    pt.m_index1 = c.index1;
    for (const btManifoldPoint& old : previous_) {
      if (old.m_partId0 == c.side && old.m_index0 == c.index0 && old.m_index1 == c.index1) {
        pt.m_appliedImpulse = old.m_appliedImpulse;
        pt.m_appliedImpulseLateral1 = old.m_appliedImpulseLateral1;
        pt.m_appliedImpulseLateral2 = old.m_appliedImpulseLateral2;
        pt.m_lifeTime = old.m_lifeTime + 1;
        ++batch_.warm_started;
        break;
      }
    }
    held.manifolds[written / MANIFOLD_CACHE_SIZE]->addManifoldPoint(pt, /*isPredictive=*/true);
    ++written;
  };
  for (size_t i : chosen_touching_) write(touching_[i]);
  for (size_t i : chosen_gaps_) write(gaps_[i]);
  batch_.points += written;
}

void BatchDispatcher::release(PairManifolds& held) {
  for (btPersistentManifold* m : held.manifolds) releaseManifold(m);
  held.manifolds.clear();
}

}  // namespace rtcd::sim
