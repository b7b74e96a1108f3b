// A host that finds rtcd with find_package and detects one contact.
#include <cstdio>

#include "rtcd/backend.hpp"

#include <rtcd/narrow_phase.hpp>

int main() {
  auto narrow = rtcd::make_narrow_phase("auto");
  auto a = narrow->add_shape(std::make_shared<rtcd::Shape>(rtcd::Box{{0.5, 0.5, 0.5}}));
  auto b = narrow->add_shape(std::make_shared<rtcd::Shape>(rtcd::Box{{0.6, 0.6, 0.6}}));
  rtcd::Pose pb;
  pb.position = {1.0, 0.0, 0.0};
  const rtcd::BodyPair pair{narrow->add_body(a, {}), narrow->add_body(b, pb)};
  const auto result = narrow->detect(std::span(&pair, 1));
  std::printf("%s: %zu contacts\n", narrow->name().c_str(), result.contacts.size());
  return result.contacts.size() == 4 ? 0 : 1;
}
