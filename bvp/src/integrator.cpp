/// @file integrator.cpp
/// @brief Fixed-step RK4 and the CVODE wrapper.
#include "tdcr/bvp/integrator.hpp"

#include <cvode/cvode.h>
#include <nvector/nvector_serial.h>
#include <sundials/sundials_context.h>
#include <sunnonlinsol/sunnonlinsol_fixedpoint.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <exception>
#include <limits>
#include <stdexcept>
#include <utility>

#include "tdcr/core/error.hpp"

namespace tdcr::bvp {

namespace {
/// CVODE's flag names, without CVodeGetReturnFlagName (which returns malloc'd memory).
const char* cvode_flag_name(int flag) {
  switch (flag) {
    case CV_SUCCESS: return "CV_SUCCESS";
    case CV_TSTOP_RETURN: return "CV_TSTOP_RETURN";
    case CV_TOO_MUCH_WORK: return "CV_TOO_MUCH_WORK";
    case CV_TOO_MUCH_ACC: return "CV_TOO_MUCH_ACC";
    case CV_ERR_FAILURE: return "CV_ERR_FAILURE";
    case CV_CONV_FAILURE: return "CV_CONV_FAILURE";
    case CV_RHSFUNC_FAIL: return "CV_RHSFUNC_FAIL";
    case CV_FIRST_RHSFUNC_ERR: return "CV_FIRST_RHSFUNC_ERR";
    case CV_REPTD_RHSFUNC_ERR: return "CV_REPTD_RHSFUNC_ERR";
    case CV_UNREC_RHSFUNC_ERR: return "CV_UNREC_RHSFUNC_ERR";
    case CV_NLS_INIT_FAIL: return "CV_NLS_INIT_FAIL";
    case CV_NLS_SETUP_FAIL: return "CV_NLS_SETUP_FAIL";
    case CV_NLS_FAIL: return "CV_NLS_FAIL";
    case CV_MEM_FAIL: return "CV_MEM_FAIL";
    case CV_MEM_NULL: return "CV_MEM_NULL";
    case CV_ILL_INPUT: return "CV_ILL_INPUT";
    case CV_NO_MALLOC: return "CV_NO_MALLOC";
    case CV_TOO_CLOSE: return "CV_TOO_CLOSE";
    case CV_VECTOROP_ERR: return "CV_VECTOROP_ERR";
    case CV_CONTEXT_ERR: return "CV_CONTEXT_ERR";
    default: return "CV_UNKNOWN_FLAG";
  }
}

}  // namespace

Integrator::~Integrator() = default;

double Integrator::relative_noise() const { return std::numeric_limits<double>::epsilon(); }

// ---------------------------------------------------------------------------------------------
// RK4

Rk4Integrator::Rk4Integrator(int steps, double max_step) { set_mesh(steps, max_step); }

void Rk4Integrator::set_mesh(int steps, double max_step) {
  if (steps < 1) throw InputError("solver.rk4_steps", std::to_string(steps), "must be >= 1");
  if (!(max_step > 0.0)) throw InputError("solver.rk4_max_step", format_value(max_step), "must be positive");
  steps_ = steps;
  max_step_ = max_step;
}

void Rk4Integrator::ensure_size(int n) {
  if (n == dim_) return;
  k1_.assign(n, 0.0);
  k2_.assign(n, 0.0);
  k3_.assign(n, 0.0);
  k4_.assign(n, 0.0);
  tmp_.assign(n, 0.0);
  dim_ = n;
}

bool Rk4Integrator::integrate(const OdeSystem& system, double s0, double s1, double* y) {
  const int n = system.dimension();
  ensure_size(n);
  last_error_.clear();
  int steps = steps_;
  if (std::isfinite(max_step_))
    steps = std::max(steps, static_cast<int>(std::ceil(std::abs(s1 - s0) / max_step_ - 1e-9)));
  const double h = (s1 - s0) / steps;
  double* k1 = k1_.data();
  double* k2 = k2_.data();
  double* k3 = k3_.data();
  double* k4 = k4_.data();
  double* t = tmp_.data();
  for (int step = 0; step < steps; ++step) {
    // s from the step index, not by accumulation, so the last stage lands exactly on s1.
    const double s = s0 + step * h;
    const double s_mid = s + 0.5 * h;
    const double s_end = (step + 1 == steps) ? s1 : s0 + (step + 1) * h;
    system.rhs(s, y, k1);
    for (int i = 0; i < n; ++i) t[i] = y[i] + 0.5 * h * k1[i];
    system.rhs(s_mid, t, k2);
    for (int i = 0; i < n; ++i) t[i] = y[i] + 0.5 * h * k2[i];
    system.rhs(s_mid, t, k3);
    for (int i = 0; i < n; ++i) t[i] = y[i] + h * k3[i];
    system.rhs(s_end, t, k4);
    for (int i = 0; i < n; ++i) y[i] += (h / 6.0) * (k1[i] + 2.0 * (k2[i] + k3[i]) + k4[i]);
  }
  rhs_evaluations_ += 4 * steps;
  for (int i = 0; i < n; ++i)
    if (!std::isfinite(y[i])) {
      last_error_ = "rk4: non-finite state at s = " + format_value(s1) + " (component " +
                    std::to_string(i) + ")";
      return false;
    }
  return true;
}

// ---------------------------------------------------------------------------------------------
// CVODE

struct CvodeIntegrator::Impl {
  double rtol, atol;
  long max_steps;
  SUNContext ctx = nullptr;
  N_Vector y = nullptr;
  SUNNonlinearSolver nls = nullptr;
  void* mem = nullptr;
  int dim = -1;
  bool initialised = false;  // CVodeInit done: later calls use CVodeReInit
  const OdeSystem* system = nullptr;
  int nrhs = 0;
  long nsteps_total = 0;
  std::string message;
  std::exception_ptr exception;

  Impl(double r, double a, long m) : rtol(r), atol(a), max_steps(m) {
    if (SUNContext_Create(nullptr, &ctx) != 0 || !ctx)
      throw std::runtime_error("CvodeIntegrator: SUNContext_Create failed");
  }
  ~Impl() {
    destroy();
    if (ctx) SUNContext_Free(&ctx);
  }
  void destroy() {
    if (mem) CVodeFree(&mem);
    if (nls) SUNNonlinSolFree(nls);
    if (y) N_VDestroy(y);
    mem = nullptr;
    nls = nullptr;
    y = nullptr;
    dim = -1;
    initialised = false;
  }
  void build(int n) {
    destroy();
    y = N_VNew_Serial(n, ctx);
    if (!y) throw std::runtime_error("CvodeIntegrator: N_VNew_Serial failed");
    mem = CVodeCreate(CV_ADAMS, ctx);
    if (!mem) throw std::runtime_error("CvodeIntegrator: CVodeCreate failed");
    if (CVodeSetErrHandlerFn(mem, &Impl::on_error, this) != CV_SUCCESS)
      throw std::runtime_error("CvodeIntegrator: CVodeSetErrHandlerFn failed");
    dim = n;
  }

  static void on_error(int, const char* module, const char* function, char* msg, void* user) {
    auto* self = static_cast<Impl*>(user);
    self->message = std::string(module ? module : "CVODE") + "/" + (function ? function : "?") +
                    ": " + (msg ? msg : "");
  }

  static int rhs_fn(sunrealtype s, N_Vector yy, N_Vector yd, void* user) {
    auto* self = static_cast<Impl*>(user);
    try {
      ++self->nrhs;
      const double* yv = N_VGetArrayPointer(yy);
      double* dv = N_VGetArrayPointer(yd);
      self->system->rhs(s, yv, dv);
      for (int i = 0; i < self->dim; ++i)
        if (!std::isfinite(dv[i])) return 1;  // recoverable: CVODE retries with a smaller step
      return 0;
    } catch (...) {
      self->exception = std::current_exception();
      return -1;
    }
  }

  // Called after CVodeInit/ReInit: options that Init resets or that need the memory.
  bool configure(std::string& err) {
    int ret = CVodeSStolerances(mem, rtol, atol);
    if (ret == CV_SUCCESS) ret = CVodeSetUserData(mem, this);
    if (ret == CV_SUCCESS) ret = CVodeSetMaxNumSteps(mem, max_steps);
    if (ret == CV_SUCCESS) ret = CVodeSetMaxHnilWarns(mem, -1);  // no t+h==t warnings
    if (ret != CV_SUCCESS) {
      err = std::string("cvode configuration: ") + cvode_flag_name(ret) + ": " + message;
      return false;
    }
    return true;
  }
};

CvodeIntegrator::CvodeIntegrator(double rtol, double atol, long max_steps) {
  if (!(rtol > 0.0) || !std::isfinite(rtol))
    throw InputError("solver.cvode_rtol", format_value(rtol), "must be positive and finite");
  if (!(atol > 0.0) || !std::isfinite(atol))
    throw InputError("solver.cvode_atol", format_value(atol), "must be positive and finite");
  if (max_steps < 1)
    throw InputError("cvode.max_steps", std::to_string(max_steps), "must be >= 1");
  impl_ = std::make_unique<Impl>(rtol, atol, max_steps);
}

CvodeIntegrator::~CvodeIntegrator() = default;
CvodeIntegrator::CvodeIntegrator(CvodeIntegrator&&) noexcept = default;
CvodeIntegrator& CvodeIntegrator::operator=(CvodeIntegrator&&) noexcept = default;

int CvodeIntegrator::rhs_evaluations() const { return impl_->nrhs; }
double CvodeIntegrator::relative_noise() const { return impl_->rtol; }
long CvodeIntegrator::steps_taken() const { return impl_->nsteps_total; }

bool CvodeIntegrator::integrate(const OdeSystem& system, double s0, double s1, double* y) {
  Impl& m = *impl_;
  last_error_.clear();
  const int n = system.dimension();
  if (n < 1) {
    last_error_ = "cvode: system dimension must be >= 1";
    return false;
  }
  if (s1 == s0) return true;  // CVODE refuses tout == t0; nothing to do anyway
  if (n != m.dim) m.build(n);

  double* yv = N_VGetArrayPointer(m.y);
  for (int i = 0; i < n; ++i) yv[i] = y[i];
  m.message.clear();
  m.system = &system;
  m.exception = nullptr;

  int ret;
  if (!m.initialised) {
    ret = CVodeInit(m.mem, &Impl::rhs_fn, s0, m.y);
    if (ret == CV_SUCCESS) {
      // Adams + fixed-point iteration: the non-stiff pairing (no Jacobian, no linear solver).
      m.nls = SUNNonlinSol_FixedPoint(m.y, 0, m.ctx);
      ret = m.nls ? CVodeSetNonlinearSolver(m.mem, m.nls) : CV_MEM_FAIL;
    }
    if (ret == CV_SUCCESS) m.initialised = true;
  } else {
    ret = CVodeReInit(m.mem, s0, m.y);
  }
  if (ret != CV_SUCCESS) {
    last_error_ = std::string("cvode init: ") + cvode_flag_name(ret) + ": " + m.message;
    m.system = nullptr;
    return false;
  }
  if (!m.configure(last_error_)) {
    m.system = nullptr;
    return false;
  }
  // The stop time keeps CVODE from stepping past s1 (and evaluating the RHS beyond the
  // interval, e.g. past a disk where the model's loads change).
  ret = CVodeSetStopTime(m.mem, s1);
  long before = 0;
  CVodeGetNumSteps(m.mem, &before);
  sunrealtype s_reached = s0;
  if (ret == CV_SUCCESS) ret = CVode(m.mem, s1, m.y, &s_reached, CV_NORMAL);
  long after = 0;
  CVodeGetNumSteps(m.mem, &after);
  m.nsteps_total += after - before;
  m.system = nullptr;

  if (m.exception) {
    std::exception_ptr e = m.exception;
    m.exception = nullptr;
    m.destroy();  // CVODE memory is mid-step: start afresh next time
    std::rethrow_exception(e);
  }
  if (ret < 0) {
    last_error_ = std::string(cvode_flag_name(ret)) + " at s = " + format_value(s_reached) + ": " +
                  m.message;
    return false;
  }
  for (int i = 0; i < n; ++i) {
    if (!std::isfinite(yv[i])) {
      last_error_ = "cvode: non-finite state at s = " + format_value(s_reached);
      return false;
    }
    y[i] = yv[i];
  }
  return true;
}

std::unique_ptr<Integrator> make_integrator(const IntegratorOptions& options) {
  switch (options.method) {
    case IntegratorMethod::Cvode:
      return std::make_unique<CvodeIntegrator>(options.cvode_rtol, options.cvode_atol);
    default:
      return std::make_unique<Rk4Integrator>(options.rk4_steps, options.rk4_max_step);
  }
}

}  // namespace tdcr::bvp
