// Typed errors: every failure names what is wrong and, where there is one,
// the first offending element.
#pragma once

#include <cstdint>
#include <optional>
#include <stdexcept>
#include <string>

#include "rtcd/export.hpp"

namespace rtcd {
RTCD_PUBLIC_BEGIN

// Base of every error the library throws.
class Error : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

enum class MeshErrorKind {
  empty,
  non_finite_coordinate,
  index_out_of_range,
  repeated_vertex,
  zero_area_triangle,
  non_manifold_edge,
  inconsistent_winding,
  out_of_range,         // coordinates or size outside what single precision answers (mesh.hpp)
  inverted,             // a closed mesh whose triangles all face inward (negative volume)
  file,  // unreadable or unparsable file
};

const char* to_string(MeshErrorKind kind);

class MeshError : public Error {
 public:
  MeshError(MeshErrorKind kind, std::optional<uint32_t> vertex, std::optional<uint32_t> triangle,
            const std::string& message)
      : Error(message), kind_(kind), vertex_(vertex), triangle_(triangle) {}
  MeshErrorKind kind() const { return kind_; }
  std::optional<uint32_t> vertex() const { return vertex_; }
  std::optional<uint32_t> triangle() const { return triangle_; }

 private:
  MeshErrorKind kind_;
  std::optional<uint32_t> vertex_;
  std::optional<uint32_t> triangle_;
};

// A configuration value out of range, or two that contradict each other.
class ConfigError : public Error {
 public:
  using Error::Error;
};

// An unknown or unavailable backend; the message lists what is available.
class BackendError : public Error {
 public:
  using Error::Error;
};

// A bad call: unknown body or shape id, malformed pose, a pair of one body.
class UsageError : public Error {
 public:
  using Error::Error;
};

RTCD_PUBLIC_END
}  // namespace rtcd
