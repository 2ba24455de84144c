// Private to models/vc: a VC workspace bound to one input, and what both formulations share
// (the loads at the current load factor, the disk point loads, a shot from the base, the tendon
// displacements).
#pragma once

#include <memory>
#include <vector>

#include <Eigen/Core>

#include "tdcr/models/model_problem.hpp"
#include "physics/contact_law.hpp"
#include "physics/load_case.hpp"
#include "tdcr/bvp/integrator.hpp"
#include "tdcr/models/cosserat_rod.hpp"
#include "tdcr/models/vc.hpp"
#include "vc/vc_dual.hpp"
#include "vc/vc_rhs.hpp"

namespace tdcr {

namespace vc {
class FrictionRod;
}

using Vec6 = Eigen::Matrix<double, 6, 1>;

struct VcWorkspace::Impl {
  explicit Impl(const VcModel& model);
  ~Impl();

  // The bound input (bind_input), its loads at load factor `lambda` (set_load_factor).
  const VcModel* model = nullptr;  ///< The owner, while a solve runs.
  physics::LoadCase loads;
  cosserat::Section section;              ///< Backbone weight at the current load factor.
  std::vector<vc::SegmentLoads> segments;  ///< One per segment, never resized (rods point in).
  double lambda = 1.0;
  unsigned long loads_version = 0;  ///< Changes whenever the bound loads do (memoised shots).
  bool per_segment = false;  ///< DisplacementConvention::PerSegment.
  int tendon_count = 0;

  // Integration, rebuilt when the integration options change.
  SolverOptions integration;
  std::unique_ptr<bvp::Integrator> shot_integrator;
  std::unique_ptr<bvp::Integrator> final_integrator;  ///< Null with CVODE (lengths in every shot).
  long retired_rhs = 0;                               ///< Evaluations of replaced integrators.
  /// The stability test's coarse RK4 mesh (solve/stability_mesh.hpp); null with CVODE (the test
  /// then takes shot_integrator).
  std::unique_ptr<bvp::Rk4Integrator> stability_integrator;
  // The stability test's buffers (vc_stability.cpp): kept, so that a test allocates none once warm.
  std::vector<Frame> stability_frames;
  std::vector<BackboneSample> stability_samples;
  std::vector<Vec6> stability_wrench;
  /// Per disk interval, the start and end coordinates per start perturbation (its transfer).
  std::vector<Eigen::Matrix<double, 12, 12>> stability_in, stability_end;
  Eigen::VectorXd stability_y0, stability_y1, stability_y;
  std::unique_ptr<vc::TendonRod> shot_rod;            ///< Lengths only with CVODE.
  std::unique_ptr<vc::TendonRod> final_rod;           ///< With lengths; watches `degeneracy`.
  vc::Degeneracy degeneracy;                          ///< Of the last final pass.
  // Tendon friction (vc_friction.hpp): these rods instead, with tension states (decided once).
  bool friction = false;
  std::unique_ptr<vc::FrictionRod> friction_shot_rod;
  std::unique_ptr<vc::FrictionRod> friction_final_rod;
  Eigen::VectorXd y;                                  ///< 18 + tendon_count (+ tendon_count: tensions).
  std::vector<double> segment_lengths;                ///< [segment * tendon_count + k] at segment ends.

  // Contact (docs/contact.md; single shooting, vc_single_shooting.cpp): the bound input's
  // obstacles, the robot's surfaces, the law and the candidates, whose forces act at their disks
  // among the disk point loads (disk_point_loads; reactions, not scaled by the load factor).
  std::vector<Obstacle> obstacles;
  contact::Surfaces surfaces;
  contact::Law law;
  std::vector<contact::Candidate> contacts;

  // The formulations, built on first use.
  std::unique_ptr<detail::ModelProblem> single;
  std::unique_ptr<detail::ModelProblem> multiple;

  bool lengths_in_shots() const { return !final_integrator; }
  bvp::Integrator& final_pass_integrator() { return final_integrator ? *final_integrator : *shot_integrator; }
  bvp::Integrator& stability_pass_integrator() {
    return stability_integrator ? *stability_integrator : *shot_integrator;
  }
};

namespace vc {

/// What a shot records.
struct Record {
  std::vector<Frame>* frames = nullptr;
  std::vector<BackboneSample>* samples = nullptr;
  std::vector<double>* segment_end_lengths = nullptr;  ///< [segment * K + k]; needs length states.
  std::vector<double>* end_tensions = nullptr;         ///< With friction: each tendon's at its end.
};

/// Bind the workspace to `input` and `options`: loads at load factor 1, section, integrators.
void bind_input(VcWorkspace::Impl& W, const VcModel& model, const ModelInput& input, const SolverOptions& options);
/// Scale every load by `lambda` (allocation-free).
void set_load_factor(VcWorkspace::Impl& W, double lambda);
/// Displacement input: tendon index[i] pulls with T[i] (N) at every load factor until the next
/// bind (detail::ModelProblem::set_driven_tensions); the bound input must tension them.
void set_driven_tensions(VcWorkspace::Impl& W, const std::vector<int>& index, const Eigen::VectorXd& T);
/// The wrench z just distal of a disk's kinks, z = G(z) (vc_shooting.cpp says how); z in: the
/// start. False, z unspecified, if it did not settle (no root near the start: a continuing
/// tendon at its geometric limit just distal of the disk). force_scale and moment_scale scale
/// the force and moment rows of the tests.
bool kink_fixed_point(const KinkMap<double>& G, double force_scale, double moment_scale, Vec6& z);
/// Point loads at disk j, the end of an interval of segment i, applied to the rod state y (its
/// first 18 values): tendon terminations (Eq. 40-41), the disk's weight and the kink forces of
/// passing tendons. False if the kink fixed-point iteration did not settle. T: double, or Dual
/// (with the derivatives; the kinks' by the implicit function theorem).
template <typename T>
bool disk_point_loads(const VcWorkspace::Impl& W, int i, int j, T* y);
/// One shot from the base with unknowns x = (n(0), m(0)) through W.y: false if the integration
/// failed, else `res` = (n(L+) - F_tip, m(L+) - M_tip). Rod: TendonRod, or FrictionRod. `base`:
/// the base frame to start from (null: p = 0, R = I, the clamp; the stability test perturbs it).
template <class Rod>
bool shoot(VcWorkspace::Impl& W, bvp::Integrator& integrator, Rod& rod, const Vec6& x, Vec6& res, const Record* rec,
           const Frame* base = nullptr);
/// `shoot` with the shot (or, `final`, the final pass's) integrator and rod, with friction or not.
bool shoot(VcWorkspace::Impl& W, bool final, const Vec6& x, Vec6& res, const Record* rec);
/// Whether the exact Jacobian of `shoot` is available: with RK4 (the derivative of the discrete
/// map); CVODE's error-controlled map is differentiated by finite differences.
bool has_exact_jacobian(const VcWorkspace::Impl& W);
/// `shoot` with the shot integrator and its exact Jacobian J = d res / d x (vc_jacobian.cpp):
/// one pass of dual numbers through the same RK4 steps and disk point loads.
bool shoot_jacobian(VcWorkspace::Impl& W, const Vec6& x, Vec6& res, Mat6& J);
/// Whether the last final pass (at the load factor where a loading path stopped) had a tensioned
/// tendon at its geometric limit (curvature x offset >= physics::kTendonLimitNear): the reason.
bool tendon_limit(const VcWorkspace::Impl& W, double threshold, std::string& why);
/// Tendon displacements (Eq. 56) from the tendon lengths at every segment end.
void tendon_displacements(const VcWorkspace::Impl& W, const std::vector<double>& segment_lengths,
                          std::vector<double>& displacements);

/// The formulations (vc_single_shooting.cpp, vc_multiple_shooting.cpp) on a workspace.
std::unique_ptr<detail::ModelProblem> make_single_shooting(VcWorkspace::Impl& W);
std::unique_ptr<detail::ModelProblem> make_multiple_shooting(VcWorkspace::Impl& W);

}  // namespace vc

}  // namespace tdcr
