/// @file integrator.hpp
/// @brief Initial value problems y' = f(s, y) behind one interface: a fixed-step classical RK4
/// (the fast, allocation-free path) and SUNDIALS CVODE (Adams, error controlled: the reference).
#pragma once

#include <limits>
#include <memory>
#include <string>
#include <vector>

namespace tdcr::bvp {

/// @brief A first-order ODE system dy/ds = f(s, y) of fixed dimension.
///
/// Raw pointers so that implementations can Eigen::Map them onto fixed-size types
/// (e.g. Eigen::Map<const Eigen::Matrix<double, 18, 1>>) with no allocation or copy.
class OdeSystem {
 public:
  virtual ~OdeSystem() = default;
  /// @brief Number of states (length of y and dyds).
  virtual int dimension() const = 0;
  /// @brief Evaluate dyds = f(s, y). s is the independent variable (arc length, m, in tdcr).
  /// Must not allocate: it is the innermost loop of every shooting model. Writing NaN or Inf
  /// makes the integration fail (RK4) or retry with a smaller step (CVODE).
  virtual void rhs(double s, const double* y, double* dyds) const = 0;
};

/// @brief Integrates an OdeSystem from s0 to s1 in place.
class Integrator {
 public:
  virtual ~Integrator();
  /// @brief Integrate y from s0 to s1 (s1 < s0 integrates backwards).
  /// @param system The ODE; its dimension() is the length of y.
  /// @param s0 Initial value of the independent variable (arc length, m, in tdcr).
  /// @param s1 Final value of the independent variable.
  /// @param y In: state at s0, out: state at s1 (length system.dimension()).
  /// @return false on failure (non-finite state, too much work, step too small). y is then
  /// unspecified.
  virtual bool integrate(const OdeSystem& system, double s0, double s1, double* y) = 0;
  /// @brief Short name for reports: "rk4" or "cvode".
  virtual std::string name() const = 0;
  /// @brief Right-hand side evaluations since construction (a cost measure for benchmarks).
  virtual int rhs_evaluations() const { return rhs_evaluations_; }
  /// @brief Relative accuracy of the map y(s0) -> y(s1) as a function of y(s0): machine
  /// epsilon for a fixed-step method (a smooth map), about the relative tolerance for an
  /// error-controlled one (its step sequence changes with y(s0)). Finite differences through
  /// the integrator should use increments of about sqrt(relative_noise()).
  virtual double relative_noise() const;
  /// @brief Text of the last failure ("" if none), e.g. CVODE's error message.
  virtual std::string last_error() const { return last_error_; }

 protected:
  int rhs_evaluations_ = 0;  ///< Maintained by derived classes.
  std::string last_error_;   ///< Set by derived classes when integrate() fails.
};

/// @brief Classical 4th-order Runge-Kutta with fixed, equal steps per integrate().
///
/// Global error O(h^4): halving the step divides it by ~16. Each integrate() call takes
/// max(steps, ceil(|s1 - s0| / max_step)) equal steps: at least `steps` per shooting interval,
/// and never a step longer than `max_step`, so that long intervals (one disk per segment) are as
/// accurate as short ones. Stage buffers are sized on the first call for a given dimension and
/// reused, so integrate() allocates nothing once warm. No error control: choose the settings from
/// a convergence study (IntegratorOptions::rk4_steps, IntegratorOptions::rk4_max_step).
class Rk4Integrator : public Integrator {
 public:
  /// @param steps Minimum steps per integrate() call (>= 1; throws InputError otherwise).
  /// @param max_step Longest step (> 0, in the units of s; infinity: exactly `steps` steps).
  explicit Rk4Integrator(int steps, double max_step = std::numeric_limits<double>::infinity());
  bool integrate(const OdeSystem& system, double s0, double s1, double* y) override;
  std::string name() const override { return "rk4"; }
  /// @brief Minimum steps per integrate() call.
  int steps() const { return steps_; }
  /// @brief Longest step.
  double max_step() const { return max_step_; }
  /// @brief A new mesh for later integrate() calls (same checks as the constructor): lets a
  /// caller refine the steps without rebuilding what holds this integrator.
  void set_mesh(int steps, double max_step);

 private:
  void ensure_size(int n);
  int steps_;
  double max_step_;
  int dim_ = -1;
  std::vector<double> k1_, k2_, k3_, k4_, tmp_;
};

/// @brief SUNDIALS CVODE with Adams-Moulton (orders 1-12) and a fixed-point corrector: the
/// Cosserat rod ODEs are not stiff, so no Jacobian or linear solver is needed.
///
/// The CVODE memory is created on the first call and re-initialised (CVodeReInit) on later
/// calls; it is rebuilt only when the dimension changes. Errors are captured in last_error(),
/// never printed. Movable, not copyable.
class CvodeIntegrator : public Integrator {
 public:
  /// @param rtol Relative tolerance (> 0).
  /// @param atol Absolute tolerance (> 0), in the units of y.
  /// @param max_steps Internal step limit per integrate() call.
  explicit CvodeIntegrator(double rtol = 1e-8, double atol = 1e-10, long max_steps = 100000);
  ~CvodeIntegrator() override;
  /// @brief Takes over the CVODE memory, tolerances and counters of another integrator. The
  /// moved-from integrator may only be destroyed or assigned to.
  CvodeIntegrator(CvodeIntegrator&&) noexcept;
  /// @brief Takes over another integrator's CVODE memory (this one's is freed). The moved-from
  /// integrator may only be destroyed or assigned to.
  CvodeIntegrator& operator=(CvodeIntegrator&&) noexcept;
  CvodeIntegrator(const CvodeIntegrator&) = delete;
  CvodeIntegrator& operator=(const CvodeIntegrator&) = delete;

  bool integrate(const OdeSystem& system, double s0, double s1, double* y) override;
  std::string name() const override { return "cvode"; }
  int rhs_evaluations() const override;
  /// @brief The relative tolerance (see Integrator::relative_noise).
  double relative_noise() const override;
  /// @brief Internal CVODE steps since construction.
  long steps_taken() const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

/// @brief Which Integrator make_integrator() builds.
enum class IntegratorMethod {
  Rk4,   ///< Rk4Integrator: fixed steps, allocation free.
  Cvode  ///< CvodeIntegrator: Adams, error controlled.
};

/// @brief Settings of make_integrator(): the method and the settings of each method (those of
/// the other method are ignored). The defaults are tdcr's (the models layer fills them from its
/// solver options).
struct IntegratorOptions {
  /// The integrator to build. Default IntegratorMethod::Rk4.
  IntegratorMethod method = IntegratorMethod::Rk4;
  /// RK4: minimum steps per integrate() call (count, >= 1). Default 8.
  int rk4_steps = 8;
  /// RK4: longest step (units of the independent variable, m in tdcr; > 0, infinity: exactly
  /// rk4_steps steps). Default 1e-3.
  double rk4_max_step = 1e-3;
  /// CVODE: relative tolerance (dimensionless, > 0). Default 1e-8.
  double cvode_rtol = 1e-8;
  /// CVODE: absolute tolerance (units of the state, > 0). Default 1e-10.
  double cvode_atol = 1e-10;
};

/// @brief The integrator selected by options.method: Rk4Integrator(options.rk4_steps,
/// options.rk4_max_step) or CvodeIntegrator(options.cvode_rtol, options.cvode_atol). Throws
/// InputError on settings of the selected method out of range.
std::unique_ptr<Integrator> make_integrator(const IntegratorOptions& options);

}  // namespace tdcr::bvp
