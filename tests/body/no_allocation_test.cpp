// Model evaluation is the fitter's hot path: after the first call it must not allocate.
// Counts malloc calls by interposing malloc (own binary; not under AddressSanitizer, which
// owns malloc itself).
#include <gtest/gtest.h>

#include <cstdlib>
#include <vector>

#include "body/body_evaluator.hpp"
#include "body/template_generator.hpp"

// GCC says so with __SANITIZE_ADDRESS__, clang 14 only through __has_feature.
#if defined(__SANITIZE_ADDRESS__)
#define POSEFUSE_UNDER_ASAN 1
#elif defined(__has_feature)
#if __has_feature(address_sanitizer)
#define POSEFUSE_UNDER_ASAN 1
#endif
#endif

#if !defined(POSEFUSE_UNDER_ASAN)
extern "C" void* __libc_malloc(size_t size);
namespace {
long g_malloc_calls = 0;
}
extern "C" void* malloc(size_t size) {
  ++g_malloc_calls;
  return __libc_malloc(size);
}
#endif

namespace posefuse::body {
namespace {

TEST(BodyEvaluator, EvaluateDoesNotAllocateAfterTheFirstCall) {
#if defined(POSEFUSE_UNDER_ASAN)
  GTEST_SKIP() << "malloc is owned by AddressSanitizer";
#else
  const auto model = make_template(Sex::kMale);
  const PoseLayout layout = PoseLayout::upper_body();
  BodyEvaluator eval(model, layout);
  Eigen::VectorXd beta = Eigen::VectorXd::Constant(10, 0.3), theta = Eigen::VectorXd::Constant(layout.size(), 0.1);
  eval.evaluate(beta, theta, Derivatives::kPoseAndShape);
  for (Derivatives what : {Derivatives::kNone, Derivatives::kPose, Derivatives::kPoseAndShape}) {
    const long before = g_malloc_calls;
    for (int i = 0; i < 10; ++i) {
      theta[7] = 0.01 * i;
      eval.evaluate(beta, theta, what);
    }
    EXPECT_EQ(g_malloc_calls - before, 0) << static_cast<int>(what);
  }
  const std::vector<int> vertices = {0, 5, 17};
  const long before = g_malloc_calls;
  eval.evaluate(beta, theta, Derivatives::kPoseOnRequest);
  eval.compute_vertex_pose_jacobians(vertices);
  EXPECT_EQ(g_malloc_calls - before, 0);
#endif
}

}  // namespace
}  // namespace posefuse::body
