// Private to models/: what the lumped static models CCsub and PRB share around their residuals.
// Both cut the robot into subsegments between disks with a few unknowns each, share the
// recursive statics (subsegment_statics.hpp), and differ only in their kinematics and
// constitutive residuals: a LumpedBody (immutable, owned by the model) says those, a
// LumpedProblem (one per workspace) binds an input and gives the solve driver the rest.
//
// Formulations of the same equations (lumped_model.hpp, LumpedFormulation):
//  - recursive: the m unknowns x_j of each loaded subsegment; frames follow from the base, the
//    distal wrenches from the tip (dense Jacobian, dense LU: ~J^3);
//  - banded (lumped_banded.cpp): besides x_j, the pose (p_j, rotation vector th_j) of disk j and
//    the distal wrench (F_j, M_j) are unknowns; residuals of subsegment j are its constitutive
//    law, pose continuity with disk j-1 and the balance of disk j (tendon forces of disks j-1,
//    j, j+1): a block-banded Jacobian (declared pattern, grouped finite differences, KLU: ~J);
//  - reduced (Automatic from LumpedBody::banded_from on): the recursive unknowns and residual,
//    each Newton step solved with the structured recursive Jacobian's block LU in its
//    quasiseparable generators, or as a block-banded system on KLU where that loses accuracy
//    (lumped_structured.cpp: ~J).
// Both give the same solution; Solution::unknowns always holds the x_j of all N subsegments.
#pragma once

#include <memory>
#include <vector>

#include <Eigen/Core>

#include "physics/contact_law.hpp"
#include "tdcr/core/contact_geometry.hpp"
#include "tdcr/models/model_problem.hpp"
#include "lumped/subsegment_statics.hpp"
#include "tdcr/bvp/sparse_lu.hpp"
#include "tdcr/models/lumped_model.hpp"

namespace tdcr::detail {

class LumpedProblem;

/// Eigen's allFinite() in one vectorised pass (it compares x - x with x - x, about 13
/// instructions a coefficient: 2 % of a PRB dynamics run, callgrind): x * 0 is zero for a
/// finite x and NaN for an infinite or NaN one, and so is their sum.
template <class Derived>
bool all_finite(const Eigen::DenseBase<Derived>& a) {
  return (a.derived().array() * 0.0).sum() == 0.0;
}

/// Geometry of one subsegment in the frame of its base disk j-1.
struct SubsegmentPose {
  Mat3 R;       ///< Rotation of disk j relative to disk j-1.
  Vec3 p;       ///< Centre O_j.
  Vec3 c;       ///< Centre of mass of the backbone of the subsegment.
  Vec3 aux[7];  ///< Model-specific points (PRB: joint centres 0..2, link midpoints 3..6).
  double cphi = 1.0, sphi = 0.0;  ///< PRB: cos and sin of the bending-plane angle of the unknowns.
};

/// The first derivatives of a SubsegmentPose in the unknowns x_j (frame of disk j-1), for the
/// bodies' velocity Jacobians in the dynamics (lumped_dynamics_mechanics.cpp): column i of
/// unknown i: the rotation's rate w[i] = vee(dR/dx_i R^T), the end's dp[i] = dp/dx_i and (PRB)
/// the link midpoints' dmid[k][i] = d aux[3 + k] / dx_i.
struct SubsegmentRates {
  Vec3 w[5], dp[5];
  Vec3 dmid[4][5];
};

/// The subsegments of one lumped model, their stiffness and kinematics.
class LumpedBody {
 public:
  LumpedBody(const Robot& robot, const TendonRouting& routing, const Effects& effects, int per_subsegment,
             LumpedFormulation formulation, int banded_from);
  virtual ~LumpedBody();

  /// Geometry of subsegment j (1-based) from its unknowns xj (per_subsegment values).
  virtual void local(int j, const double* xj, SubsegmentPose& g) const = 0;
  /// local() and its first derivatives in closed form (g and d at xj), if the model has them
  /// (false: the dynamics differentiate local() numerically).
  virtual bool local_rates(int j, const double* xj, SubsegmentPose& g, SubsegmentRates& d) const {
    (void)j, (void)xj, (void)g, (void)d;
    return false;
  }
  /// The unknowns that can move link midpoint k (PRB's aux[3 + k]) as a bit mask over the columns
  /// of SubsegmentRates::dmid[k]: the others are zero at every x_j. The dynamics skip them, and
  /// take a link that none moves as part of its base disk's rigid body.
  virtual unsigned link_unknowns(int k) const {
    (void)k;
    return (1u << per_subsegment) - 1u;
  }
  /// The same at axial stretch `stretch` (SubsegmentLoads::stretch): the tendons' compression
  /// shortens a subsegment uniformly and leaves its bend and twist, so its points scale.
  void pose(int j, const double* xj, double stretch, SubsegmentPose& g) const;
  /// local_rates() at axial stretch `stretch` (points and their rates scaled as pose()).
  bool pose_rates(int j, const double* xj, double stretch, SubsegmentPose& g, SubsegmentRates& d) const;
  /// The problem of a new workspace.
  virtual std::unique_ptr<LumpedProblem> make_problem() const = 0;
  /// Disk frames 0..N (base disk first) from the unknowns of subsegments 1..J (x holds at least
  /// per_subsegment J values); subsegments beyond J are straight. Poses (if given, index 1..J)
  /// and centroids (if given, base frame, index 1..N) receive the subsegment geometry.
  /// With from > 1, frames 0..from-1 (and poses, centroids below from) are taken as they are and
  /// only frames from..N are computed. `stretch`: the subsegments' stretches of the bound input
  /// (SubsegmentLoads::stretch_data(); nullptr when inextensible).
  void compute_frames(const double* x, int J, const double* stretch, Frame* frames, SubsegmentPose* poses = nullptr,
                      Vec3* centroids = nullptr, int from = 1) const;
  /// Disk frames for a full unknown vector (per_subsegment N values; InputError otherwise) at the
  /// stretches `stretch` (nullptr: inextensible).
  std::vector<Frame> disk_frames(const Eigen::VectorXd& x, const double* stretch) const;
  /// True if solved in the banded formulation (LumpedFormulation::Banded).
  bool banded() const;
  /// True if J loaded subsegments are solved in the recursive unknowns with reduced Newton
  /// steps (the structured recursive Jacobian, LumpedFormulation::Automatic from banded_from on).
  bool reduced(int J) const;

  SubsegmentStatics statics;
  double EI = 0.0, GJ = 0.0;  ///< Bending and torsional stiffness (N m^2).
  double length = 0.0;        ///< Robot length L (m).
  int per_subsegment = 0;     ///< Unknowns m per subsegment.
  int N = 0;                  ///< Subsegments.
  LumpedFormulation formulation = LumpedFormulation::Automatic;
  int banded_from = 0;  ///< Automatic: banded from this many loaded subsegments on.
  /// Automatic: the contact solve's structured Newton steps (KLU on the contact system,
  /// lumped_contact_jacobian.cpp) from this many subsegments on; dense LU below.
  int contact_structured_from = 0;
  double backbone_radius = 0.0;     ///< Outer radius of the backbone (m): its contact surface.
  std::vector<double> disk_radius;  ///< Radius of disk j (index 0..N; m): its contact surface.
};

/// The LumpedModel::BodyFactory of a body class constructible from (robot, routing, effects,
/// formulation).
template <class Body>
std::unique_ptr<LumpedBody> make_body(const Robot& robot, const TendonRouting& routing, const Effects& effects,
                                      LumpedFormulation formulation) {
  return std::make_unique<Body>(robot, routing, effects, formulation);
}

/// One workspace's solve of a lumped model: its residual system (the parameter is the load
/// factor: every load of the bound input scales with it), Newton memory and buffers, sized once.
/// Unknowns: those of the J loaded subsegments in the formulation chosen at bind (m J recursive,
/// (m + 12) J banded); Solution::unknowns holds the x_j of all N (zero beyond J), so warm starts
/// work across inputs with another J and either formulation.
class LumpedProblem : public ModelProblem, public bvp::ParameterizedSystem {
 public:
  explicit LumpedProblem(const LumpedBody& body);

  /// Resolve the loads of `input` and choose the formulation (allocation-free after the first
  /// bind of a given J).
  void bind(const ModelInput& input);
  /// Dynamics (lumped_dynamics.cpp): bind `input` with every subsegment among the unknowns (in
  /// motion the unloaded ones bend too), in the recursive unknowns; residual() then takes and
  /// gives the per_subsegment N values of all subsegments.
  void bind_all(const ModelInput& input);
  /// The subsegments' stretches of the bound input (SubsegmentLoads::stretch_data()).
  const double* stretch() const { return loads_.stretch_data(); }

  bvp::ParameterizedSystem* system() override { return this; }
  bvp::NewtonSolver& newton() override { return newton_; }
  /// Dense LU for the recursive formulation, KLU for the banded one.
  void adjust(bvp::NewtonOptions& options) const override;
  /// Warm starts: modified Newton from the previous solve's Jacobian, unless that solve needed
  /// many iterations (its Jacobian is then too far from this one's).
  void adjust_warm(bvp::NewtonOptions& options, bool same_input) const override;
  /// The model's cold guess (guess_x), lifted to the formulation's unknowns.
  void cold_guess(Eigen::VectorXd& y) final;
  void rest_state(Eigen::VectorXd& y) final;
  bool warm_guess(const Solution& previous, Eigen::VectorXd& y) final;
  void extract(const Eigen::VectorXd& y, bool evaluated, Solution& solution) final;
  bool set_driven_tensions(const std::vector<int>& index, const Eigen::VectorXd& T) final;
  /// The disk frames of the x_j and the chords between them (no residual).
  bool tendon_pulls(const Eigen::VectorXd& y, Eigen::VectorXd& d) final;
  /// Eigenvalues of the Jacobian of the constitutive residuals in the x_j (lumped_stability.cpp).
  /// With contact candidates (contact_stability()): rigid contacts that carry force constrain
  /// the test to the tangent space of their gaps; compliant ones add their penalty's stiffness.
  Stability stability(const Eigen::VectorXd& y, double load_factor) final;
  /// The test of a direct answer under loads: first a sufficient test (the structured Jacobian,
  /// Newton's last where it is near the answer, else the answer's; a block Cholesky factorisation
  /// of its balanced symmetric part, O(J)), stability() where it does not prove the answer stable
  /// (lumped_stability.cpp). What the automatic rule calls for a cold direct answer under external
  /// loads; tests compare it with stability().
  Stability direct_stability(const Eigen::VectorXd& y, double load_factor) final;
  /// Where the sufficient test applies (no obstacles, tendon friction or banded formulation, where
  /// direct_stability() is the eigen test, several solves): it adds 14 % (CCsub) and 22 % (PRB)
  /// to the median loaded cold solve of bench_loaded, within the automatic rule's 25 %
  /// (docs/models.md, "Stability").
  bool automatic_stability_under_loads() const final {
    return !contact_ && !banded_ && !body_.statics.friction();
  }

  int size() const final { return stride() * loads_.active + static_cast<int>(contacts_.size()); }
  /// Contact (lumped_contact.cpp): the free-space answer y is checked against the obstacles of
  /// the bound input; where it penetrates one, the candidate contacts near it join the unknowns
  /// (their force magnitudes) and the residuals (complementarity), and Newton goes on from there,
  /// until no candidate is left out that the answer penetrates. Done without obstacles.
  Completion complete(Eigen::VectorXd& y, const bvp::NewtonOptions& options, SolverSummary& summary) final;
  void set_parameter(double lambda) final { loads_.set_load_factor(lambda); }
  bool residual(const Eigen::Ref<const Eigen::VectorXd>& y, Eigen::Ref<Eigen::VectorXd> f) final;
  /// residual() at y with the disk frames 0..N and the subsegments' poses 1..N of y given (the
  /// dynamics' twists have just computed them from the same poses: compute_frames() would
  /// repeat them to the bit). Only bound by bind_all() in the recursive form without contact
  /// candidates or friction; otherwise residual().
  bool residual_with_frames(const Eigen::Ref<const Eigen::VectorXd>& y, const Frame* frames,
                            const SubsegmentPose* poses, Eigen::Ref<Eigen::VectorXd> f);
  /// The driver's final check right after Newton: where the last residual() call was at y at the
  /// same load factor and nothing has changed the equations or the evaluated state since (the
  /// usual end of a solve: KINSOL's last call is at the point it returns), that call's values.
  bool final_residual(const Eigen::VectorXd& y, Eigen::Ref<Eigen::VectorXd> f) final;
  /// True if the last residual() call was at y at the current load factor and the evaluated state
  /// (frames_, poses_, centroids_, F_, M_) is still that call's.
  bool evaluated_at(const Eigen::Ref<const Eigen::VectorXd>& y) const;
  /// Viscous damping of the x_j (snap landings): r + rate s (x - x_ref), s the unknowns' scales.
  /// The joint laws (bending about a joint axis, twist) are components of the potential's
  /// gradient, so this is an implicit Euler step of an overdamped motion in them; PRB's
  /// bending-plane law (Eq. 52-53, the plane along the moment) is that gradient component
  /// divided by the subsegment's bend angle (so of the opposite sign where that angle is negative),
  /// and is damped only weakly (its scale 1e-4). Recursive form, with dense or structured (reduced) Newton steps,
  /// without friction (the Jacobians this class assembles); false otherwise (banded form,
  /// friction).
  bool set_damping(const Eigen::Ref<const Eigen::VectorXd>& x_ref, double rate) final;
  const bvp::SparsityPattern* sparsity() const final { return banded_ ? &pattern_ : nullptr; }
  void unknown_scale(Eigen::Ref<Eigen::VectorXd> s) const final;
  // Structured Newton step (lumped_structured.cpp): the recursive form's Jacobian factors
  // (structured_jacobian) solved as a block-banded system by KLU; the iterations are those of
  // the recursive form at a cost linear in J.
  bool has_newton_step() const final { return reduced_ || (contact_step_ && !contacts_.empty()); }
  // Recursive form without friction: the dense Jacobian by structured forward differences
  // (structured_jacobian, then two small products); also what path following's bordered
  // systems use in the reduced form. With contact candidates the same differences carry the
  // contact forces, and their columns and the complementarity rows are added
  // (lumped_contact_jacobian.cpp).
  bool has_jacobian() const final { return !banded_ && !body_.statics.friction(); }
  // Its diagonal blocks are forward differences (of first-order accuracy): differential
  // kinematics keeps its own central differences.
  bool jacobian_is_forward_difference() const final { return true; }
  bool jacobian(const Eigen::Ref<const Eigen::VectorXd>& x, const Eigen::Ref<const Eigen::VectorXd>& f,
                Eigen::Ref<Eigen::MatrixXd> J) final;
  /// The diagonal blocks of jacobian() only (m x m J, block j in columns m (j - 1)...), from the
  /// same structured differences: the dynamics' chain Newton matrix (lumped_dynamics.cpp). False
  /// with contact candidates (their columns are not in these blocks) or where not finite.
  bool diagonal_jacobian(const Eigen::Ref<const Eigen::VectorXd>& x, const Eigen::Ref<const Eigen::VectorXd>& f,
                         Eigen::Ref<Eigen::MatrixXd> blocks);
  bool setup_newton_step(const Eigen::Ref<const Eigen::VectorXd>& x, const Eigen::Ref<const Eigen::VectorXd>& f) final;
  bool solve_newton_step(Eigen::Ref<Eigen::VectorXd> b) final;
  /// The banded system's pattern and the column colouring of its grouped differences, for the
  /// loaded subsegments of the last bind (built only for the banded formulation; tests).
  const bvp::SparsityPattern& banded_pattern() const { return pattern_; }
  const std::vector<int>& banded_groups() const { return groups_; }

 protected:
  /// Constitutive residuals (per_subsegment values) of subsegment j with geometry g: F, M
  /// (about O_j) the distal wrench and W the backbone weight of the subsegment (zero without
  /// gravity), all in the frame of disk j-1.
  virtual void constitutive(int j, const double* xj, const SubsegmentPose& g, const Vec3& F, const Vec3& M,
                            const Vec3& W, double* r) const = 0;
  /// d r_j / d(F, M, W) of constitutive() at the given geometry (m x 9, column-major in L), if
  /// the model has it in closed form; false: the Jacobian takes forward differences instead.
  virtual bool load_jacobian(int j, const double* xj, const SubsegmentPose& g, const Vec3& F, const Vec3& M,
                             const Vec3& W, double* L) const {
    (void)j, (void)xj, (void)g, (void)F, (void)M, (void)W, (void)L;
    return false;
  }
  /// The x_j of the cold guess, or with `rest` of the rest state (the straight robot): zeros
  /// unless overridden (CCsub: fixed-point passes from the straight robot; PRB: the straight
  /// robot with its bending planes set by the load, and for the cold guess fixed-point passes
  /// from there).
  virtual void guess_x(Eigen::VectorXd& x, bool rest) { (void)rest; x.setZero(body_.per_subsegment * active()); }
  /// A fixed-point map of subsegment j's constitutive law: the x_j (in `next`) that satisfy it
  /// for the given loads (frame of disk j-1, as constitutive()) with the geometry g of the
  /// current xj held where the law needs it; false if the model has none. `weight` (m values,
  /// ones on entry): the weights of |next - xj| in the contraction test of fixed_point_passes
  /// (e.g. 0 for an angle that is only a chart).
  virtual bool fixed_point(int j, const double* xj, const SubsegmentPose& g, const Vec3& F, const Vec3& M,
                           const Vec3& W, double* next, double* weight) const {
    (void)j, (void)xj, (void)g, (void)F, (void)M, (void)W, (void)next, (void)weight;
    return false;
  }
  /// Up to `passes` fixed-point (Picard) passes x <- P(x) of every loaded subsegment at full
  /// load, P the model's fixed_point() in the shape x: a cold guess. Passes stop where they stop
  /// contracting (the largest weighted change not halved, or not finite): with a load parameter
  /// above about 1 the map can expand. Leaves the load factor as it was.
  void fixed_point_passes(Eigen::VectorXd& x, int passes);
  /// Called with the x_j of a warm start (e.g. to take gauge references from it).
  virtual void on_warm(const Eigen::VectorXd& x) { (void)x; }
  /// The stability test's chart (lumped_stability.cpp): rewrites x (the x_j of every loaded
  /// subsegment) as the same shape in the chart where the constitutive laws are B Q with B
  /// positive, and moves any gauge reference along; leave_stability_chart() restores the
  /// references. Default: x unchanged (CCsub's curvature components have one chart).
  virtual void enter_stability_chart(Eigen::VectorXd& x) { (void)x; }
  virtual void leave_stability_chart() {}
  /// One stability test's stay in that chart: entered at construction (x rewritten), left on
  /// every return of the test.
  class StabilityChartScope {
   public:
    StabilityChartScope(LumpedProblem& p, Eigen::VectorXd& x) : p_(p) { p_.enter_stability_chart(x); }
    ~StabilityChartScope() { p_.leave_stability_chart(); }
    StabilityChartScope(const StabilityChartScope&) = delete;
    StabilityChartScope& operator=(const StabilityChartScope&) = delete;

   private:
    LumpedProblem& p_;
  };
  /// Scale of x_j (per_subsegment values; default ones).
  virtual void x_scale(double* s) const;
  /// The unknown of subsegment j (index within x_j, in the stability chart) whose law is not a
  /// positive multiple of the potential's gradient at x_j, so that a mode of the stability test
  /// made of it decides nothing; -1: none (PRB: the bending-plane angle of a subsegment with an
  /// inflection inside, lumped_stability.cpp).
  virtual int ill_posed_unknown(const double* xj) const {
    (void)xj;
    return -1;
  }

  /// The equations changed (gauge references, damping, loads other than by set_parameter): the
  /// last residual() is no longer final_residual()'s.
  void residual_changed() {
    last_valid_ = false;
    ++equations_serial_;
  }
  /// Frames, poses, centroids (if the backbone weight acts) and distal wrenches at x_j.
  void evaluate(const double* x);
  /// Moment about O_{j-1} (base frame) of everything distal of disk j-1 at the last evaluate().
  Vec3 base_moment(int j) const {
    const Vec3& o = frames_[j - 1].p;
    Vec3 m = M_[j] + (frames_[j].p - o).cross(F_[j]);
    if (backbone_weight_on()) m += (centroids_[j] - o).cross(backbone_weight(j));
    return m;
  }

  int active() const { return loads_.active; }
  bool banded() const { return banded_; }
  bool backbone_weight_on() const { return loads_.loads.has_backbone_weight(); }
  Vec3 backbone_weight(int j) const { return body_.statics.backbone_weight(loads_, j); }

  SubsegmentLoads loads_;
  std::vector<Frame> frames_;
  std::vector<SubsegmentPose> poses_;
  std::vector<Vec3> centroids_, F_, M_;

 private:
  // --- Contact (lumped_contact.cpp, docs/contact.md) ---
  // A candidate contact (physics/contact_law.hpp): a disk's rim or the backbone at a disk's
  // centre against an obstacle; its force magnitude (scaled by contact_force_scale_) is an
  // unknown after the x_j.
  using ContactCandidate = contact::Candidate;
  contact::Law contact_law() const {
    return contact::Law{contact_stiffness_, contact_force_scale_, contact_length_scale_, contact_min_};
  }
  bool contact_ = false;  // the bound input has obstacles
  std::vector<Obstacle> obstacles_;
  double contact_stiffness_ = 0.0;  // N/m; 0: rigid
  bool contact_min_ = false;        // complete()'s first steps: rigid contact as min(a, b) = 0
  double contact_force_scale_ = 1.0, contact_length_scale_ = 1.0;
  std::vector<ContactCandidate> contacts_;
  contact::Surfaces contact_surfaces_;  // the body's backbone and disk radii
  Eigen::VectorXd contact_x_;      // complete(): the x_j of all N subsegments
  std::vector<Frame> contact_frames_;
  void bind_contact(const ModelInput& input);
  // Every subsegment loaded, the recursive form: the contact system's unknowns.
  void enter_contact_mode();
  // The contact forces on the disks (disk_f_, disk_m_) at the evaluated frames, then the distal
  // wrenches (evaluate() with candidates).
  void evaluate_contacts();
  // The complementarity residuals of the candidates (after evaluate()).
  void contact_residuals(double* f) const;
  // y (the x_j of the loaded subsegments) extended by the candidates' force unknowns.
  void append_contact_unknowns(Eigen::VectorXd& y) const;
  // The candidates' force unknowns read from y.
  void read_contact_unknowns(const double* y);
  // Solution::contacts from the candidates at the evaluated state.
  void report_contacts(Solution& solution) const;
  // complete(): the pairs the shape x (all N subsegments) penetrates that are not candidates;
  // with `add`, those and every pair within the margin join the candidates. True if any penetrates.
  bool penetrating_pairs(const Eigen::VectorXd& x, bool add);
  bool warm_contacts(const Solution& previous);
  // complete(): penetrating_pairs() of shapes between the unknowns `from` and `to` (all N
  // subsegments), the first that penetrates a pair left out adding its candidates; true if one did.
  bool swept_pairs(const Eigen::VectorXd& from, const Eigen::VectorXd& to);
  // Whether the shapes between `from` and `to` pass through a finite obstacle's middle (every pair).
  bool passes_through(const Eigen::VectorXd& from, const Eigen::VectorXd& to);
  // penetrating_pairs() of disk frames 0..N.
  bool penetrating_frames(const Frame* frames, bool add);
  // The sweeps' shapes: the disk frames of `from` and `to` (sweep_frames), and contact_frames_ a
  // fraction t of the way between them (frames_between).
  void sweep_frames(const Eigen::VectorXd& from, const Eigen::VectorXd& to);
  void frames_between(double t);
  std::vector<Frame> sweep_from_, sweep_to_;
  bool passed_through_ = false;  // penetrating_pairs() found a finite obstacle penetrated deeply
  double deepest_ = 0.0;         // and the deepest penetration (m) of its last shape
  // complete(): load the robot from rest with the candidates (load factor 0 -> 1 in steps, new
  // contacts added as they close); y the answer at full load; false if a step could not be solved.
  bool load_with_contacts(Eigen::VectorXd& y, const bvp::NewtonOptions& nopt, SolverSummary& work);
  // lumped_contact_jacobian.cpp: the contact terms of structured_jacobian(). contact_loads():
  // the contact wrench on every disk at the evaluated state (jac_cf_, jac_cm_ about O_j), and
  // per candidate the response of its force (pulled back by the motion: force, moment about the
  // origin; jac_A_, 6 x 6) and of its gap (jac_a_) to a rigid twist (w, v) of its disk, with
  // B_j = sum of jac_A_ over the candidates at disks >= j (jac_B_).
  // contact_column(): column c (of subsegment k, increment h) moves frame k to fk and every
  // frame distal of it by (Q, t); adds the contact forces of disk k at fk and the change of those
  // distal of k beyond the rigid motion to the distal wrench (Fk, Mk about fk.p) of disk k, and
  // keeps the column's twist (jac_Xi_) for the rows distal of k and the gaps.
  void contact_loads();
  void contact_column(int k, int c, const Mat3& Q, const Vec3& t, const Frame& fk, const Frame& base_k1, double h,
                      Vec3& Fk, Vec3& Mk);
  // jacobian() with candidates: the structured blocks plus the contact terms, dense.
  bool contact_jacobian(Eigen::Ref<Eigen::MatrixXd> Jm);
  // d complementarity residual / d gap and / d b of candidate i at the evaluated state.
  void contact_derivatives(std::size_t i, double& da, double& db) const;
  // The structured Newton step with candidates: the block-banded system of lumped_structured.cpp
  // with the twists' partial sums tau_j (6) in place of the rotations', the force unknowns and
  // the gap rows; fill(put) emits its entries in a fixed order (pattern, values).
  template <class Put>
  void contact_structured_entries(Put&& put) const;
  bool contact_setup_newton_step(const Eigen::Ref<const Eigen::VectorXd>& x, const Eigen::Ref<const Eigen::VectorXd>& f);
  bool contact_solve_newton_step(Eigen::Ref<Eigen::VectorXd> b);
  Eigen::MatrixXd jac_A_, jac_a_, jac_B_, jac_Xi_;
  std::vector<Vec3> jac_cf_, jac_cm_;
  bool contact_step_ = false;  // contact mode solves its Newton steps structured
  bvp::SparsityPattern cstruct_pattern_;
  std::vector<int> cstruct_pos_, cstruct_disks_;  // positions; the candidates' disks it was built for
  std::vector<double> cstruct_values_;
  Eigen::VectorXd cstruct_rhs_;
  int cstruct_J_ = -1;
  bool cstruct_external_ = false;
  bvp::SparseLu contact_lu_{1e-3};

  int stride() const { return banded_ ? body_.per_subsegment + 12 : body_.per_subsegment; }
  bool recursive_residual(const double* x, double* f);
  // Frames from subsegment k on, the loads of disks k-1.. (kept in disk_f_, disk_m_) and all
  // distal wrenches; the state below comes from the previous evaluate_from (no friction).
  void evaluate_from(const double* x, int k);
  // The constitutive residuals of every loaded subsegment at the evaluated state.
  void constitutive_all(const double* x, double* f);
  // lumped_banded.cpp
  bool banded_residual(const double* y, double* f);
  void lift(const Eigen::VectorXd& x, Eigen::VectorXd& y);
  void lift_banded(const Eigen::VectorXd& x, Eigen::VectorXd& y);
  void gather_x(const Eigen::VectorXd& y, Eigen::VectorXd& x) const;
  void build_pattern();
  void banded_scale(double* s) const;

  const LumpedBody& body_;
  bvp::NewtonSolver newton_;
  Actuation::DisplacementConvention convention_ = Actuation::DisplacementConvention::AtBase;
  bool banded_ = false;
  bool reduced_ = false;
  double damping_ = 0.0;  // set_damping's rate, reference and the unknowns' scales
  Eigen::VectorXd damping_ref_, damping_scale_, damping_f_;
  // Structured Newton steps (lumped_structured.cpp): the recursive Jacobian's factors as a
  // block-banded system in (d_j, s_j, t_j), its pattern (per J and external loads), the CSC
  // positions in fill order, values and right-hand side. KLU: analysed once per pattern,
  // refactorised per step. The solve gives a Newton direction, judged afterwards on the recursive
  // residual, so a refactorisation that may lose up to three digits is kept (KINSOL's own systems
  // keep two); a fresh pivoting factorisation costs about 3 refactorisations.
  void build_structured_pattern();
  bool klu_setup_newton_step();
  bool klu_solve_newton_step(Eigen::Ref<Eigen::VectorXd> b);
  // The same Jacobian's block LU without pivoting between blocks, in its quasiseparable
  // generators (lumped_structured.cpp): O(J) small fixed-size products, no sparse matrix. The
  // diagonal blocks Delta_j (their inverses kept), P_j (m x 6) and Q_j (3 x m) of the factors;
  // every solve is checked by its residual and the KLU system above takes over where the
  // factors lost accuracy (a Delta_j singular or with growth).
  template <int Rows>
  bool qs_factor();
  template <int Rows>
  void qs_solve(double* b) const;
  template <int Rows>
  void qs_multiply(const double* x, double* y) const;
  Eigen::MatrixXd qs_G_, qs_inv_, qs_P_, qs_Q_;
  Eigen::VectorXd qs_b_, qs_r_;
  bool qs_factored_ = false;
  bool klu_factored_ = false;
  long jac_serial_ = 0;  // structured_jacobian() calls: the factors' values are still jac_*'s
  long qs_serial_ = -1;
  bvp::SparsityPattern struct_pattern_;
  std::vector<int> struct_pos_;
  std::vector<double> struct_values_;
  Eigen::VectorXd struct_rhs_;
  int struct_J_ = -1;
  bool struct_external_ = false;
  bvp::SparseLu lu_{1e-3};
  bvp::SparsityPattern pattern_;
  std::vector<int> groups_;  // column colouring of pattern_ (banded formulation; tests)
  int pattern_J_ = -1;
  Eigen::VectorXd x_;  // x_j of the loaded subsegments (guesses, lifting)
  Eigen::VectorXd pull_x_;          // tendon_pulls(): the x_j of all N subsegments
  std::vector<Frame> pull_frames_;  // and their disk frames
  std::vector<Vec3> disk_f_, disk_m_;  // disk loads of the banded residual
  int last_iterations_ = 0;  // Newton iterations of the last solve (adjust_warm)
  // The last residual() call (final_residual): its point, values and load factor; valid while
  // the evaluated state (frames_, F_, M_, ...) is still that call's.
  Eigen::VectorXd last_y_, last_f_;
  double last_lambda_ = 0.0;
  bool last_valid_ = false;
  Eigen::VectorXd jac_x_, jac_f_, jac_uscale_;  // jacobian(): perturbed x, its residual, scales
  // jacobian(): the distal wrenches split into the part moving with the frames (tendons) and the
  // external part (see split_external_loads), the perturbed loads of two disks.
  void split_external_loads();
  // The factors of the recursive Jacobian at x (f: the residual there): jac_diag_, jac_E_, jac_D_,
  // jac_dW_, jac_Om_ (see lumped_structured.cpp); false if a value is not finite. With
  // diagonal_only, jac_diag_ alone (diagonal_jacobian(): the others are left as they were).
  bool structured_jacobian(const Eigen::Ref<const Eigen::VectorXd>& x, const Eigen::Ref<const Eigen::VectorXd>& f,
                           bool diagonal_only = false);
  // structured_jacobian() of the undamped residual, given the (possibly damped) f at x: the
  // damping's diagonal is added by the caller (jacobian(), setup_newton_step()).
  bool undamped_structured_jacobian(const Eigen::Ref<const Eigen::VectorXd>& x,
                                    const Eigen::Ref<const Eigen::VectorXd>& f, bool diagonal_only = false);
  // jacobian(): the residuals' response to distal wrench changes and to distal rotations.
  void load_sensitivities();
  template <int Rows>
  void load_sensitivities_m();
  // jacobian(): the off-diagonal blocks from the factors.
  template <int Rows>
  void offdiagonal_blocks(Eigen::Ref<Eigen::MatrixXd> Jm) const;
  Eigen::MatrixXd jac_E_, jac_D_, jac_dW_, jac_Om_, jac_diag_;
  bool jac_external_ = false;
  // The point of the last structured_jacobian() without contact candidates (the solve's
  // unknowns), its load factor and the equations it was taken of (equations_serial_: counts
  // residual_changed() calls, which mark changes of the equations such as gauge references):
  // direct_stability() reuses Newton's last Jacobian where it is that of its answer's equations
  // and near it. jac_equations_ -1: none.
  Eigen::VectorXd jac_at_;
  double jac_lambda_ = 0.0;
  long jac_equations_ = -1;
  long equations_serial_ = 0;
  std::vector<Vec3> jac_FT_, jac_MT_, jac_FE_, jac_pure_, jac_df_, jac_dm_;
  Eigen::VectorXd next_x_;  // fixed_point_passes()
  // direct_stability(): the scaled Jacobian's block tridiagonal part, its balancing, the
  // generators of the balanced symmetric part.
  Eigen::MatrixXd stab_G_, stab_up_, stab_lo_, stab_P_, stab_Q_;
  Eigen::VectorXd stab_r_, stab_s_, stab_t_, stab_y_;
  // direct_stability()'s sufficient test: true and the margin (the smallest eigenvalue of the
  // balanced symmetric part) if it proves the answer stable; at x_ in the stability chart.
  // `reuse`: the Jacobian factors jac_* are those of Newton's last Jacobian of these equations in
  // this chart (at jac_at_), tried first; `reused`: they proved it.
  bool proven_stable(double& margin, bool& reused, bool reuse);
  // stability() of an answer with contact candidates (lumped_stability.cpp): y the contact
  // system's unknowns (the x_j, then the candidates' scaled forces).
  Stability contact_stability(const Eigen::VectorXd& y);
  std::vector<Mat3> jac_G_;
};

/// The workspace of CCsub and PRB: one problem (its state, Newton memory, buffers). Declared
/// here (not in lumped_model.cpp) so that tests can reach the residual system of a workspace.
class LumpedWorkspace final : public ModelWorkspace {
 public:
  LumpedWorkspace(const StaticModel& owner, const LumpedBody& body);
  ~LumpedWorkspace() override;
  std::unique_ptr<LumpedProblem> problem;
};

}  // namespace tdcr::detail
