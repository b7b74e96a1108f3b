// `rtcd check MESH...`: what each mesh file holds and which of its defects
// change inside/outside answers. Exit 0 fit, 1 a defect, 2 unreadable.
#pragma once

#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "rtcd/mesh_check.hpp"

namespace rtcd::app {

struct CheckOptions {
  std::vector<std::string> files;
  bool json = false;
  bool weld = false;
};

int run_check(const CheckOptions& options);

// One mesh's findings as `rtcd check --json` prints them.
nlohmann::json to_json(const MeshCheck& check);

}  // namespace rtcd::app
