// The BVH traversal with a stack far shallower than its trees, so subtrees
// past the stack go by escape links: the answers must not change.
#define RTCD_BVH_STACK 2
#include "bvh_answers.hpp"

namespace rtcd::test {
namespace {

TEST(Bvh, AnswersAsTheBruteForceWithAShallowStack) {
  size_t stack_needed = 0;
  expect_bvh_answers_as_the_brute_force(stack_needed);
  EXPECT_GT(stack_needed, size_t(RTCD_BVH_STACK) + RTCD_BVH_WIDTH - 1)
      << "no tree outgrew the stack: the escape-link path went untested";
}

}  // namespace
}  // namespace rtcd::test
