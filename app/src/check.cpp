// `rtcd check` (see check.hpp).
#include "rtcd/app/check.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <optional>
#include <iostream>
#include <sstream>

#include <nlohmann/json.hpp>

#include "rtcd/clock.hpp"
#include "rtcd/distance_bound.hpp"
#include "rtcd/error.hpp"
#include "rtcd/mesh_check.hpp"
#include "rtcd/shape.hpp"

namespace rtcd::app {
namespace {

constexpr int kFit = 0, kDefect = 1, kUnreadable = 2;

std::string plural(const std::string& element, size_t count) {
  if (count == 1) return element;
  if (element == "vertex") return "vertices";
  if (element == "mesh") return "meshes";
  return element + "s";
}

std::string example_text(const MeshFinding& f) {
  std::ostringstream s;
  for (size_t i = 0; i < f.examples.size(); ++i) {
    s << (i ? ", " : "");
    const auto& e = f.examples[i];
    const char* sep = f.element == "edge" ? "-" : f.element == "triangle pair" ? "x" : " ";
    if (f.element == "vertex group") s << "(";
    for (size_t k = 0; k < e.size(); ++k) s << (k ? sep : "") << e[k];
    if (f.element == "vertex group") s << ")";
  }
  if (f.count > f.examples.size()) s << ", ...";
  return s.str();
}

// What the shape's distance bound takes (a fit mesh only: the others make
// no shape).
struct BoundFigures {
  std::array<int, 3> nodes{};
  double cell = 0.0, seconds = 0.0;
  size_t bytes = 0;
};
std::optional<BoundFigures> bound_figures(const MeshCheck& c, const MeshData& data) {
  if (!c.fit()) return std::nullopt;
  try {
    const Shape shape(Mesh(data.positions, data.triangles));
    const auto t = Clock::now();
    const DistanceBound& bound = shape.distance_bound();
    return BoundFigures{bound.nodes(), bound.cell(), seconds_since(t), bound.bytes()};
  } catch (const Error&) {
    return std::nullopt;  // fit for the method, outside what a shape takes (its size)
  }
}

void print_text(const std::string& file, const MeshCheck& c, const std::optional<BoundFigures>& bound) {
  size_t defects = 0;
  for (const auto& f : c.findings) defects += f.defect && f.count > 0;
  std::cout << file << ": " << (c.fit() ? "fit for the method" : "NOT fit for the method") << " (" << defects
            << (defects == 1 ? " defect" : " defects") << ")\n";
  std::cout << "  vertices " << c.vertices << ", triangles " << c.triangles << ", components " << c.components
            << ", " << (c.closed ? "closed" : "open") << ", signed volume " << c.signed_volume << '\n';
  if (!c.bounds.empty())
    std::cout << "  bounds (" << c.bounds.min.x() << ", " << c.bounds.min.y() << ", " << c.bounds.min.z() << ") to ("
              << c.bounds.max.x() << ", " << c.bounds.max.y() << ", " << c.bounds.max.z() << ")\n";
  for (const auto& f : c.findings) {
    if (f.count == 0) continue;
    std::cout << "  " << (f.defect ? "defect " : "note   ") << f.name << ": " << f.count << ' '
              << plural(f.element, f.count);
    if (!f.examples.empty() && !f.examples[0].empty()) std::cout << " (" << example_text(f) << ")";
    std::cout << "\n         " << f.meaning << '\n';
  }
  if (bound)
    std::cout << "  distance bound: " << bound->nodes[0] << " x " << bound->nodes[1] << " x " << bound->nodes[2]
              << " nodes, cell " << bound->cell << ", " << bound->bytes << " bytes, built in "
              << std::round(1e4 * bound->seconds) / 10
              << " ms\n";
}

}  // namespace

nlohmann::json to_json(const MeshCheck& c) {
  nlohmann::json findings = nlohmann::json::object();
  for (const auto& f : c.findings)
    findings[f.name] = {{"count", f.count}, {"defect", f.defect}, {"element", f.element},
                        {"examples", f.examples}, {"meaning", f.meaning}};
  nlohmann::json j = {{"fit", c.fit()},
                      {"vertices", c.vertices},
                      {"triangles", c.triangles},
                      {"components", c.components},
                      {"closed", c.closed},
                      {"signed_volume", c.signed_volume},
                      {"findings", findings}};
  if (!c.bounds.empty())
    j["bounds"] = {{c.bounds.min.x(), c.bounds.min.y(), c.bounds.min.z()},
                   {c.bounds.max.x(), c.bounds.max.y(), c.bounds.max.z()}};
  return j;
}

int run_check(const CheckOptions& o) {
  int code = kFit;
  nlohmann::json all = nlohmann::json::array();
  for (const auto& file : o.files) {
    try {
      MeshData data = read_mesh_file(file);
      if (o.weld) weld_coincident(data.positions, data.triangles);
      const MeshCheck c = check_mesh(data.positions, data.triangles);
      code = std::max(code, c.fit() ? kFit : kDefect);
      const std::optional<BoundFigures> bound = bound_figures(c, data);
      if (o.json) {
        nlohmann::json j = to_json(c);
        j["file"] = file;
        if (bound)
          j["distance_bound"] = {
              {"nodes", bound->nodes}, {"cell", bound->cell}, {"bytes", bound->bytes}, {"seconds", bound->seconds}};
        all.push_back(j);
      } else {
        print_text(file, c, bound);
      }
    } catch (const MeshError& e) {
      code = kUnreadable;
      if (o.json) all.push_back({{"file", file}, {"error", e.what()}});
      std::cerr << "rtcd: " << e.what() << '\n';
    }
  }
  if (o.json) std::cout << all.dump(2) << '\n';
  return code;
}

}  // namespace rtcd::app
