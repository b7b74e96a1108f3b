// Index loops that go parallel only when there is enough work: a steady step
// of a few pairs costs less on the calling thread than handing it out.
#pragma once

#include <cstddef>

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

namespace rtcd {

template <class Body>
void for_each_index(size_t count, bool parallel, const Body& body) {
  if (!parallel || count < 2) {
    for (size_t i = 0; i < count; ++i) body(i);
    return;
  }
  tbb::parallel_for(tbb::blocked_range<size_t>(0, count), [&](const tbb::blocked_range<size_t>& r) {
    for (size_t i = r.begin(); i < r.end(); ++i) body(i);
  });
}

}  // namespace rtcd
