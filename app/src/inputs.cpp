// Knobs, shape specs, poses and pose sequences: a command's inputs.
#include "rtcd/app/inputs.hpp"

#include <algorithm>
#include <charconv>
#include <cmath>
#include <fstream>
#include <iostream>
#include <sstream>

#include <nlohmann/json.hpp>

#include "rtcd/error.hpp"
#include "rtcd/mesh_check.hpp"
#include "rtcd/validation/families.hpp"

namespace rtcd::app {
namespace {

std::vector<double> parse_numbers(const std::string& text, const std::string& what) {
  std::vector<double> out;
  std::string token;
  std::string normalised = text;
  for (char& c : normalised)
    if (c == ',') c = ' ';
  std::istringstream words(normalised);
  while (words >> token) {
    double v = 0;
    const auto [end, ec] = std::from_chars(token.data(), token.data() + token.size(), v);
    if (ec != std::errc() || end != token.data() + token.size() || !std::isfinite(v))
      throw UsageError(what + ": '" + token + "' is not a finite number");
    out.push_back(v);
  }
  return out;
}

Pose pose_of_numbers(const std::vector<double>& v, const std::string& what) {
  if (v.size() != 7)
    throw UsageError(what + ": expected 7 numbers (tx ty tz qw qx qy qz), got " + std::to_string(v.size()));
  return pose_from(v.data(), what);
}

}  // namespace

Pose pose_from(const double* v, const std::string& what) {
  Pose p;
  p.position = {v[0], v[1], v[2]};
  p.orientation = Eigen::Quaterniond(v[3], v[4], v[5], v[6]);
  try {
    return checked(p);
  } catch (const UsageError& e) {
    throw UsageError(what + ": " + e.what());
  }
}

void Knobs::apply(Config& c) const {
  for (const auto& [knob, value] : set) knob->set(c, value);
}

Config Knobs::config() const {
  Config c;
  apply(c);
  return c;
}

std::string option_name(const Knob& knob) {
  std::string name = knob.name;
  std::replace(name.begin(), name.end(), '_', '-');
  return name;
}

void warn_if_self_intersecting(const Shape& shape, const std::string& name) {
  if (const Mesh* mesh = shape.mesh())
    if (const std::string warning = self_intersection_warning(*mesh, name); !warning.empty())
      std::cerr << "rtcd: warning: " << warning << '\n';
}

std::shared_ptr<const Shape> parse_shape(const std::string& spec, double sampling, const MeshOptions& options) {
  if (spec.rfind("family:", 0) == 0) {
    const auto colon = spec.rfind(':');
    const std::string body = spec.substr(colon + 1);
    if (colon < 7 || (body != "a" && body != "b"))
      throw UsageError("'" + spec + "': expected family:NAME:a or family:NAME:b");
    const validation::Family f = validation::make_family(spec.substr(7, colon - 7));
    warn_if_self_intersecting(body == "a" ? *f.a : *f.b, spec);
    return body == "a" ? f.a : f.b;
  }
  if (spec.rfind("sphere:", 0) == 0) {
    const auto v = parse_numbers(spec.substr(7), "sphere radius in '" + spec + "'");
    if (v.size() != 1) throw UsageError("'" + spec + "': expected sphere:R");
    return std::make_shared<Shape>(Sphere{v[0]}, sampling);
  }
  if (spec.rfind("box:", 0) == 0) {
    const auto v = parse_numbers(spec.substr(4), "box half extents in '" + spec + "'");
    if (v.size() != 3) throw UsageError("'" + spec + "': expected box:HX,HY,HZ");
    return std::make_shared<Shape>(Box{{v[0], v[1], v[2]}}, sampling);
  }
  auto shape = std::make_shared<Shape>(Mesh::load(spec, options));
  warn_if_self_intersecting(*shape, spec);
  return shape;
}

Pose parse_pose(const std::string& text, const std::string& what) {
  return pose_of_numbers(parse_numbers(text, what), what);
}

std::vector<SequenceStep> read_sequence(const std::string& path) {
  std::ifstream in(path);
  if (!in) throw UsageError(path + ": cannot open sequence file");
  nlohmann::json doc;
  try {
    doc = nlohmann::json::parse(in);
  } catch (const nlohmann::json::exception& e) {
    throw UsageError(path + ": not valid JSON: " + e.what());
  }
  if (!doc.is_array() || doc.empty()) throw UsageError(path + ": expected a non-empty JSON array of steps");
  std::vector<SequenceStep> steps;
  for (size_t i = 0; i < doc.size(); ++i) {
    const std::string where = path + ": step " + std::to_string(i);
    if (!doc[i].is_object()) throw UsageError(where + ": expected an object with pose_a and pose_b");
    SequenceStep s;
    for (const char* key : {"pose_a", "pose_b"}) {
      const auto it = doc[i].find(key);
      if (it == doc[i].end() || !it->is_array()) throw UsageError(where + ": missing array " + key);
      std::vector<double> v;
      for (const auto& x : *it) {
        if (!x.is_number()) throw UsageError(where + ": " + key + " holds a non-number");
        v.push_back(x.get<double>());
      }
      for (double x : v)
        if (!std::isfinite(x)) throw UsageError(where + ": " + key + " holds a non-finite number");
      (std::string(key) == "pose_a" ? s.a : s.b) = pose_of_numbers(v, where + " " + key);
    }
    steps.push_back(s);
  }
  return steps;
}

}  // namespace rtcd::app
