// scratch (not committed)
#include <chrono>
#include <cmath>
#include <cstdio>
#include <optional>
#include <cstdlib>
#include <ctime>
static double cpu_ms(){timespec t; clock_gettime(CLOCK_THREAD_CPUTIME_ID,&t); return t.tv_sec*1e3+t.tv_nsec*1e-6;}
#include "bench_common.hpp"
#include "tdcr/core/paper_robot.hpp"
using namespace tdcr;
int main(int argc, char** argv) {
  const std::string m = argc > 1 ? argv[1] : "vc";
  const int n = argc > 2 ? std::atoi(argv[2]) : 1000;
  const bool verbose = argc > 3;
  ModelKind kind = m == "vc" ? ModelKind::VC : m == "vcref" ? ModelKind::VCref : m == "ccsub" ? ModelKind::CCsub : ModelKind::PRB;
  const Robot robot = paper::robot(10);
  const double t_max = paper::max_tension(robot);
  auto input = [&](int k) {
    ModelInput in;
    in.actuation.values = {t_max * 0.5 * (1.0 - std::cos(2.0 * M_PI * k / n)), 0.0, 0.0, 0.0};
    in.loads.tip_force = Vec3(0.05, 0.0, 0.0);
    return in;
  };
  auto model = make_model(kind, robot);
  auto ws = model->make_workspace();
  SolverOptions o;
  const std::string var = argc > 4 ? argv[4] : "default";
  if (var == "h0" || var == "h1" || var == "h2") { o.integrator = IntegratorKind::FixedStepRK4; int h = var[1]-'0'; o.rk4_steps = 1 << h; o.rk4_max_step = 8e-3 / (1 << h); }
  const bool noref = argc > 5;
  std::optional<Solution> prev;
  long it = 0, re = 0, je = 0; int fail = 0;
  std::vector<Solution> kept;
  const auto t0 = std::chrono::steady_clock::now(); const double c0 = cpu_ms();
  for (int k = 1; k <= n; ++k) {
    Solution s = solve(*model, *ws, input(k), o, prev ? &*prev : nullptr);
    it += s.summary.iterations; re += s.summary.residual_evaluations; je += s.summary.jacobian_evaluations;
    if (verbose && k % (n/20) == 0) std::printf("k %d it %d re %d je %d halv %d est %.2e stab %s %s\n", k, s.summary.iterations, s.summary.residual_evaluations, s.summary.jacobian_evaluations, s.summary.rk4_halvings, s.summary.tip_error_estimate, to_string(s.stability.status).c_str(), s.summary.message.substr(0,120).c_str());
    if (!s.converged()) ++fail;
    if (k % (n/20) == 0) kept.push_back(s);
    if (s.converged()) prev = std::move(s);
  }
  const double ms = cpu_ms() - c0;
  // errors vs tight reference
  SolverOptions tight; tight.integrator = IntegratorKind::Cvode; tight.cvode_rtol = 1e-12; tight.cvode_atol = 1e-12; tight.function_tolerance = 1e-13;
  if (kind == ModelKind::CCsub || kind == ModelKind::PRB) tight = SolverOptions(), tight.function_tolerance = 1e-13;
  auto rws = model->make_workspace();
  double worst = 0;
  if (!noref) for (size_t i = 0; i < kept.size(); ++i) {
    int k = (i + 1) * (n / 20);
    Solution r = solve(*model, *rws, input(k), tight, &kept[i]);
    worst = std::max(worst, (r.tip().p - kept[i].tip().p).norm());
  }
  std::printf("%s: %.0f Hz  it/step %.2f re/step %.2f je/step %.2f fail %d worst %.2e\n", m.c_str(), 1e3 * n / ms, double(it)/n, double(re)/n, double(je)/n, fail, worst);
}
