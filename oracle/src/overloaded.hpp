// The overload set for std::visit over a Shape's geometry.
#pragma once

namespace rtcd::oracle {

template <class... F>
struct overloaded : F... {
  using F::operator()...;
};
// Explicit guide: clang before 17 has no CTAD for aggregates.
template <class... F>
overloaded(F...) -> overloaded<F...>;

}  // namespace rtcd::oracle
