// Metamorphic tests: transformations of the input whose effect on the
// contacts is known without knowing the contacts. Moving both bodies by one
// rigid motion changes nothing; swapping A and B swaps the sources; scaling
// both by s scales depths by s; renumbering triangles or vertices renumbers
// ids only.
#include <map>
#include <numeric>
#include <random>

#include <gtest/gtest.h>

#include "rtcd/mesh_gen.hpp"
#include "support.hpp"

namespace rtcd::test {
namespace {

using Eigen::Quaterniond;
using Eigen::Vector3d;
using Eigen::Vector3f;

// (source, vertex) → depth: what a contact set's vertex rays say, ids
// aside. (An edge contact's point is the middle of its crossing, computed
// from the lower-numbered end: renumbering moves it by a rounding. The
// differential tests judge edge crossings pair by pair.)
using Depths = std::map<std::pair<int, uint32_t>, double>;

Depths depths(const StepResult& r) {
  Depths d;
  for (const Contact& c : r.contacts)
    if (c.kind == ContactKind::vertex) d[{int(c.source), c.vertex}] = c.depth;
  return d;
}

// Contacts agree up to a relative tolerance; vertices within `band` of the
// surface may be on either side in one of the two. Returns how many were
// compared, for the callers' check that the test is not vacuous.
size_t expect_same(const Depths& x, const Depths& y, double band, double rel = 1e-4) {
  size_t compared = 0;
  for (const auto& [key, depth] : x) {
    const auto it = y.find(key);
    if (it == y.end()) {
      EXPECT_LT(depth, band) << "source " << key.first << " vertex " << key.second << " only in the first";
      continue;
    }
    EXPECT_NEAR(depth, it->second, rel * std::max(depth, band)) << "source " << key.first << " vertex " << key.second;
    ++compared;
  }
  for (const auto& [key, depth] : y) {
    if (!x.contains(key)) {
      EXPECT_LT(depth, band) << "source " << key.first << " vertex " << key.second << " only in the second";
    }
  }
  return compared;
}

struct Case {
  Pose a, b;
};

std::vector<Case> cases(int n) {
  std::mt19937 g(21);
  std::uniform_real_distribution<double> u(-1, 1);
  std::vector<Case> out;
  for (int i = 0; i < n; ++i) {
    const Pose a = at(Vector3d(u(g), u(g), u(g)), Quaterniond(1, u(g), u(g), u(g)));
    out.push_back({a, at(a.position + 1.2 * Vector3d(u(g), u(g), u(g)).normalized(), Quaterniond(1, u(g), u(g), u(g)))});
  }
  return out;
}

class Metamorphic : public ::testing::TestWithParam<std::string> {
 protected:
  std::shared_ptr<const Shape> a_ = shape(gen::concave_blob(902, 31, 0.7));
  std::shared_ptr<const Shape> b_ = shape(gen::concave_blob(902, 32, 1.0));
};

TEST_P(Metamorphic, RigidMotionOfBothChangesNothing) {
  const Pose motion = at(Vector3d(1234.5, -77.25, 3.0), Quaterniond(0.2, -0.7, 0.4, 0.5));
  size_t compared = 0;
  for (const Case& c : cases(10)) {
    PairRig x(GetParam(), a_, b_), y(GetParam(), a_, b_);
    compared += expect_same(depths(x.step(c.a, c.b)), depths(y.step(motion * c.a, motion * c.b)), 1e-5);
  }
  EXPECT_GT(compared, 100u) << "too few contacts: vacuous";
}

TEST_P(Metamorphic, SwappingBodiesSwapsSources) {
  size_t compared = 0;
  for (const Case& c : cases(10)) {
    PairRig x(GetParam(), a_, b_), y(GetParam(), b_, a_);
    Depths swapped;
    for (const auto& [key, depth] : depths(y.step(c.b, c.a))) swapped[{1 - key.first, key.second}] = depth;
    compared += expect_same(depths(x.step(c.a, c.b)), swapped, 1e-9, 1e-12);
  }
  EXPECT_GT(compared, 100u) << "too few contacts: vacuous";
}

Mesh scaled(const Mesh& m, float s) {
  std::vector<Vector3f> p;
  for (const auto& v : m.positions()) p.push_back(v * s);
  return Mesh(p, {m.triangles().begin(), m.triangles().end()});
}

TEST_P(Metamorphic, ScalingBothScalesDepths) {
  const float s = 8.0f;  // a power of two: scaled float coordinates are exact
  auto sa = shape(scaled(*a_->mesh(), s)), sb = shape(scaled(*b_->mesh(), s));
  const Config scaled_config;  // the derived limits scale with the shapes
  size_t compared = 0;
  for (const Case& c : cases(10)) {
    PairRig x(GetParam(), a_, b_), y(GetParam(), sa, sb, scaled_config);
    Pose ya = c.a, yb = c.b;
    ya.position *= s;
    yb.position *= s;
    Depths unscaled;
    for (const auto& [key, depth] : depths(y.step(ya, yb))) unscaled[key] = depth / s;
    compared += expect_same(depths(x.step(c.a, c.b)), unscaled, 1e-5);
  }
  EXPECT_GT(compared, 100u) << "too few contacts: vacuous";
}

// Triangles in reverse order and vertices renumbered by a fixed shuffle:
// the same contacts under the new vertex ids.
TEST_P(Metamorphic, RenumberingPermutesIdsOnly) {
  const Mesh& m = *b_->mesh();
  std::vector<uint32_t> to_new(m.vertex_count());
  std::iota(to_new.begin(), to_new.end(), 0u);
  std::shuffle(to_new.begin(), to_new.end(), std::mt19937(5));
  std::vector<Vector3f> p(m.vertex_count());
  for (size_t v = 0; v < m.vertex_count(); ++v) p[to_new[v]] = m.positions()[v];
  std::vector<Mesh::Triangle> t;
  for (size_t i = m.triangle_count(); i-- > 0;) {
    const auto& tri = m.triangles()[i];
    t.push_back({to_new[tri[0]], to_new[tri[1]], to_new[tri[2]]});
  }
  auto renumbered = shape(Mesh(p, t));
  size_t compared = 0;
  for (const Case& c : cases(10)) {
    PairRig x(GetParam(), a_, b_), y(GetParam(), a_, renumbered);
    Depths expected;
    for (const auto& [key, depth] : depths(x.step(c.a, c.b)))
      expected[{key.first, key.first == int(Side::b) ? to_new[key.second] : key.second}] = depth;
    // Depths to the nearest surface: its triangle is chosen in float (the
    // tracers' rule), so where two lie as near within float rounding the
    // lower id wins, and renumbering may pick the other, a rounding farther.
    compared += expect_same(expected, depths(y.step(c.a, c.b)), 1e-9, 1e-6);
  }
  EXPECT_GT(compared, 100u) << "too few contacts: vacuous";
}

INSTANTIATE_TEST_SUITE_P(Backends, Metamorphic, ::testing::ValuesIn(usable_backends()),
                         [](const auto& info) { return test_name(info.param); });

}  // namespace
}  // namespace rtcd::test
