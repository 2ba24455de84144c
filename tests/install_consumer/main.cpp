// A minimal research program against an installed tdcr.
#include <cstdio>

#include <tdcr/core/paper_robot.hpp>
#include <tdcr/models/static_model.hpp>

int main() {
  tdcr::Scene scene = tdcr::paper::scene(10, 2, "cc");
  const tdcr::Solution sol = tdcr::solve(scene);
  std::printf("consumer: %s\n", sol.summary.brief_report().c_str());
  std::printf("consumer: tip z = %.6f m\n", sol.tip().p.z());
  return sol.converged() ? 0 : 1;
}
