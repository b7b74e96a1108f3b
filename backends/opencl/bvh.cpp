#include "bvh.hpp"

#include <algorithm>
#include <array>

#include "rtcd/error.hpp"

namespace rtcd {
namespace {

constexpr int kBins = 16;
constexpr size_t kLeafSize = 2;  // at most this many triangles stop the split
static_assert(kLeafSize < 4, "a wide node's leaf code holds counts below 4");

struct Box {
  Eigen::Vector3f lo = Eigen::Vector3f::Constant(std::numeric_limits<float>::infinity());
  Eigen::Vector3f hi = Eigen::Vector3f::Constant(-std::numeric_limits<float>::infinity());
  void extend(const Eigen::Vector3f& p) {
    lo = lo.cwiseMin(p);
    hi = hi.cwiseMax(p);
  }
  void extend(const Box& b) {
    lo = lo.cwiseMin(b.lo);
    hi = hi.cwiseMax(b.hi);
  }
  float half_area() const {
    if ((lo.array() > hi.array()).any()) return 0.0f;
    const Eigen::Vector3f e = hi - lo;
    return e.x() * e.y() + e.y() * e.z() + e.z() * e.x();
  }
};

struct Item {
  Box box;
  Eigen::Vector3f centroid;
  uint32_t triangle;
};

class Builder {
 public:
  Builder(const Mesh& mesh, FlatBvh& out) : mesh_(mesh), out_(out) {}

  void build(std::vector<Item>& items, size_t begin, size_t end) {
    const size_t index = out_.nodes.size();
    out_.nodes.push_back({});
    Box bounds, centroids;
    for (size_t i = begin; i < end; ++i) {
      bounds.extend(items[i].box);
      centroids.extend(items[i].centroid);
    }
    const size_t count = end - begin;
    const size_t mid = count <= kLeafSize ? begin : split(items, begin, end, centroids);
    rtcd_bvh_node& node = out_.nodes[index];
    node.lo = rtcd_v3(bounds.lo.x(), bounds.lo.y(), bounds.lo.z());
    node.hi = rtcd_v3(bounds.hi.x(), bounds.hi.y(), bounds.hi.z());
    if (mid == begin) {
      node.first = rtcd_uint(out_.primitives.size());
      node.count = rtcd_uint(count);
      for (size_t i = begin; i < end; ++i) out_.primitives.push_back(primitive(items[i].triangle));
      node.escape = rtcd_uint(out_.nodes.size());
      return;
    }
    node.first = 0;
    node.count = 0;
    build(items, begin, mid);
    build(items, mid, end);
    out_.nodes[index].escape = rtcd_uint(out_.nodes.size());  // the vector may have moved
  }

 private:
  // The SAH's best split of [begin, end) over binned centroids along the
  // widest axis; the middle by count when the centroids cannot be told apart.
  size_t split(std::vector<Item>& items, size_t begin, size_t end, const Box& centroids) {
    const Eigen::Vector3f extent = centroids.hi - centroids.lo;
    int axis = 0;
    if (extent.y() > extent[axis]) axis = 1;
    if (extent.z() > extent[axis]) axis = 2;
    const size_t middle = begin + (end - begin) / 2;
    if (!(extent[axis] > 0.0f)) {
      std::nth_element(items.begin() + long(begin), items.begin() + long(middle), items.begin() + long(end),
                       [](const Item& a, const Item& b) { return a.triangle < b.triangle; });
      return middle;
    }
    auto bin_of = [&](const Item& item) {
      const int b = int(float(kBins) * (item.centroid[axis] - centroids.lo[axis]) / extent[axis]);
      return std::clamp(b, 0, kBins - 1);
    };
    std::array<Box, kBins> boxes;
    std::array<size_t, kBins> counts{};
    for (size_t i = begin; i < end; ++i) {
      const int b = bin_of(items[i]);
      boxes[b].extend(items[i].box);
      ++counts[b];
    }
    // Costs of every plane between bins, sweeping from both ends.
    std::array<float, kBins> left_cost{};
    Box acc;
    size_t n = 0;
    for (int b = 0; b < kBins - 1; ++b) {
      acc.extend(boxes[b]);
      n += counts[b];
      left_cost[b] = acc.half_area() * float(n);
    }
    acc = Box{};
    n = 0;
    float best = std::numeric_limits<float>::infinity();
    int best_plane = -1;
    for (int b = kBins - 1; b > 0; --b) {
      acc.extend(boxes[b]);
      n += counts[b];
      const float cost = left_cost[b - 1] + acc.half_area() * float(n);
      if (cost < best) {
        best = cost;
        best_plane = b;
      }
    }
    const auto first_right = std::partition(items.begin() + long(begin), items.begin() + long(end),
                                            [&](const Item& item) { return bin_of(item) < best_plane; });
    const size_t mid = size_t(first_right - items.begin());
    if (mid == begin || mid == end) {
      std::nth_element(items.begin() + long(begin), items.begin() + long(middle), items.begin() + long(end),
                       [&](const Item& a, const Item& b) { return a.centroid[axis] < b.centroid[axis]; });
      return middle;
    }
    return mid;
  }

  rtcd_bvh_primitive primitive(uint32_t triangle) const {
    rtcd_bvh_primitive p{};
    for (int k = 0; k < 3; ++k) {
      const Eigen::Vector3f& v = mesh_.positions()[mesh_.triangles()[triangle][size_t(k)]];
      p.corner[k] = rtcd_v3(v.x(), v.y(), v.z());
    }
    p.triangle = rtcd_int(triangle);
    return p;
  }

  const Mesh& mesh_;
  FlatBvh& out_;
};

float half_area(const rtcd_bvh_node& n) {
  const rtcd_vec3 e = rtcd_sub(n.hi, n.lo);
  return e.x * e.y + e.y * e.z + e.z * e.x;
}

// A wide node over the binary subtrees `slots`, opened (the inner one of
// largest box replaced by its two children) until RTCD_BVH_WIDTH, and its inner
// children's wide nodes after it; returns its index.
rtcd_int widen(FlatBvh& bvh, std::vector<rtcd_uint> slots) {
  const auto& nodes = bvh.nodes;
  while (slots.size() < RTCD_BVH_WIDTH) {
    size_t open = slots.size();
    for (size_t k = 0; k < slots.size(); ++k)
      if (nodes[slots[k]].count == 0 &&
          (open == slots.size() || half_area(nodes[slots[k]]) > half_area(nodes[slots[open]])))
        open = k;
    if (open == slots.size()) break;
    const rtcd_uint n = slots[open];
    slots[open] = n + 1;
    slots.push_back(nodes[n + 1].escape);
  }
  const auto index = rtcd_int(bvh.wide.size());
  bvh.wide.push_back({});
  for (size_t k = 0; k < RTCD_BVH_WIDTH; ++k) {
    rtcd_int child = RTCD_BVH_NO_CHILD;
    rtcd_bvh_node box{};  // no child: a box at the origin, never visited
    if (k < slots.size()) {
      box = nodes[slots[k]];
      child = box.count != 0 ? RTCD_BVH_LEAF(box.first, box.count)
                             : widen(bvh, {slots[k] + 1, nodes[slots[k] + 1].escape});
    }
    rtcd_bvh_wide_node& w = bvh.wide[size_t(index)];  // the vector may have moved
    w.lo_x[k] = box.lo.x;
    w.lo_y[k] = box.lo.y;
    w.lo_z[k] = box.lo.z;
    w.hi_x[k] = box.hi.x;
    w.hi_y[k] = box.hi.y;
    w.hi_z[k] = box.hi.z;
    w.child[k] = child;
    w.subtree[k] = k < slots.size() ? slots[k] : 0;
  }
  return index;
}

}  // namespace

FlatBvh build_flat_bvh(const Mesh& mesh) {
  FlatBvh bvh;
  const auto positions = mesh.positions();
  std::vector<Item> items;
  items.reserve(mesh.triangle_count());
  for (size_t t = 0; t < mesh.triangle_count(); ++t) {
    if (mesh.zero_area()[t]) continue;  // no query answers it
    Item& item = items.emplace_back();
    for (uint32_t v : mesh.triangles()[t]) item.box.extend(positions[v]);
    // Centroid from the box: cheap, and the split needs only an order.
    item.centroid = 0.5f * (item.box.lo + item.box.hi);
    item.triangle = uint32_t(t);
  }
  bvh.nodes.reserve(2 * items.size());
  bvh.primitives.reserve(items.size());
  if (items.empty()) return bvh;
  // Leaf codes hold first * 4 + count in an int.
  if (items.size() >= (size_t(1) << 29))
    throw Error("a mesh of " + std::to_string(items.size()) + " triangles: the BVH holds fewer than 2^29");
  Builder(mesh, bvh).build(items, 0, items.size());
  widen(bvh, {0});
  return bvh;
}

}  // namespace rtcd
