#include "tdcr/models/cc.hpp"

#include <algorithm>
#include <cmath>

#include <Eigen/Dense>

#include "tdcr/models/model_problem.hpp"
#include "tdcr/core/error.hpp"
#include "tdcr/core/lie.hpp"

namespace tdcr {

namespace {

// Shortening of tendon r over a segment of length l with curvature (kx, ky) = kappa (cos, sin),
// split into n subsegments. Fully constrained (Eq. 15): l kappa d with d = r . (cos, sin).
// Partially constrained (Eq. 20): the n chords of the tendon arc of radius 1/kappa - d over the
// angle theta = kappa l have total length (l - theta d) sinc(theta / 2n); sinc keeps kappa -> 0
// regular and theta d = l (k . r) needs no division by kappa.
double segment_shortening(const Vec3& r, double l, const Eigen::Vector2d& k, TendonPath path, int n) {
  const double theta_d = l * (k.x() * r.x() + k.y() * r.y());
  if (path == TendonPath::FullyConstrained) return theta_d;
  const double h = k.norm() * l / (2.0 * n);
  const double sinc = std::abs(h) < 1e-6 ? 1.0 - h * h / 6.0 : std::sin(h) / h;
  return l - (l - theta_d) * sinc;
}

}  // namespace

double CcArc::bending_plane() const {
  // u = kappa (-sin phi, cos phi, 0): the arc bends towards (cos phi, sin phi).
  return std::atan2(-u.x(), u.y());
}

CcModel::CcModel(const Robot& robot, const Effects& effects) : StaticModel(robot, effects) {
  // Kinematic: the arcs follow from the tendon moments at the base, no tension along a path.
  if (effects.tendon_friction.on())
    throw InputError("effects.tendon_friction", "on", "the CC model has no tendon friction; use ccsub, prb or vcref");
  // Constant curvature per segment needs tendons parallel to the backbone.
  for (std::size_t i = 0; i < this->robot().segments.size(); ++i)
    for (std::size_t k = 0; k < this->robot().segments[i].tendons.size(); ++k)
      if (this->robot().segments[i].tendons[k].routing.type != TendonRoutingSpec::Type::Straight)
        throw InputError("robot.segments[" + std::to_string(i) + "].tendons[" + std::to_string(k) + "].routing",
                         this->robot().segments[i].tendons[k].routing.type == TendonRoutingSpec::Type::Helical
                             ? "\"helical\""
                             : "\"points\"",
                         "the CC model supports straight routing only (use CCsub, PRB, VC or VCref)");
  for (const Segment& seg : this->robot().segments) {
    Eigen::MatrixXd A(seg.tendons.size(), 2);
    for (std::size_t i = 0; i < seg.tendons.size(); ++i)
      A.row(i) << seg.length * seg.tendons[i].x, seg.length * seg.tendons[i].y;
    displacement_to_curvature_.push_back(seg.tendons.empty() ? Eigen::Matrix<double, 2, Eigen::Dynamic>(2, 0)
                                                             : A.completeOrthogonalDecomposition().pseudoInverse());
  }
}

void CcModel::check_input(const ModelInput& input) const {
  StaticModel::check_input(input);
  if (input.actuation.kind != Actuation::Kind::Displacements) return;
  for (std::size_t i = 0; i < robot().segments.size(); ++i) {
    const std::size_t m = robot().segments[i].tendons.size();
    if (m < 2)
      throw InputError("robot.segments[" + std::to_string(i) + "].tendons", std::to_string(m),
                       "the CC model needs at least 2 tendons per segment for displacement input");
  }
}

std::vector<CcArc> CcModel::arcs(const ModelInput& input, double* misfit) const {
  std::vector<CcArc> out;
  arcs(input, out, misfit);
  return out;
}

void CcModel::arcs(const ModelInput& input, std::vector<CcArc>& out, double* misfit) const {
  const Robot& robot = this->robot();
  const int nseg = static_cast<int>(robot.segments.size());
  out.assign(nseg, CcArc{});
  double sq = 0.0;
  if (input.actuation.kind == Actuation::Kind::Tensions) {
    const BackboneStiffness k = robot.backbone.effective_stiffness();
    for (int s = 0; s < nseg; ++s) {
      Vec3 m = Vec3::Zero();
      double T = 0.0;
      for (const RoutedTendon& t : routing().tendons) {
        if (t.segment < s) continue;  // ended before segment s
        const double Tk = input.actuation.values[t.index];
        m += Tk * Vec3::UnitZ().cross(t.r);
        T += Tk;
      }
      out[s].u = m / k.EI;
      if (effects().shear_extension) out[s].v = Vec3(0.0, 0.0, 1.0 - T / k.EA);
    }
    if (misfit) *misfit = 0.0;
    return;
  }

  const TendonPath path = effects().tendon_path;
  const bool at_base = input.actuation.convention == Actuation::DisplacementConvention::AtBase;
  std::vector<Eigen::Vector2d> kappa(nseg, Eigen::Vector2d::Zero());
  for (int s = 0; s < nseg; ++s) {
    const Segment& seg = robot.segments[s];
    const int m = static_cast<int>(seg.tendons.size());
    Eigen::VectorXd b(m);
    std::vector<Vec3> r(m);
    for (int i = 0, k = 0; k < static_cast<int>(routing().tendons.size()); ++k) {
      const RoutedTendon& t = routing().tendons[k];
      if (t.segment != s) continue;
      double d = input.actuation.values[k];
      if (at_base)  // remove the share of the proximal segments the tendon runs through
        for (int q = 0; q < s; ++q)
          d -= segment_shortening(t.r, robot.segments[q].length, kappa[q], path, robot.segments[q].disks);
      r[i] = t.r;
      b(i) = d;
      ++i;
    }
    // Fully constrained: linear least squares, minimum norm when the tendons are collinear.
    Eigen::Vector2d k = displacement_to_curvature_[s] * b;
    if (path == TendonPath::PartiallyConstrained) {
      // Gauss-Newton from the fully constrained answer, on r_i(k) = shortening_i(k) - b_i, with
      // a forward-difference Jacobian (2 unknowns).
      for (int it = 0; it < 50; ++it) {
        Eigen::VectorXd f(m);
        Eigen::MatrixXd J(m, 2);
        for (int i = 0; i < m; ++i) f(i) = segment_shortening(r[i], seg.length, k, path, seg.disks) - b(i);
        for (int c = 0; c < 2; ++c) {
          Eigen::Vector2d kp = k;
          const double h = 1e-7 * std::max(1.0, std::abs(k(c)));
          kp(c) += h;
          for (int i = 0; i < m; ++i)
            J(i, c) = (segment_shortening(r[i], seg.length, kp, path, seg.disks) - b(i) - f(i)) / h;
        }
        const Eigen::Vector2d dk = J.completeOrthogonalDecomposition().solve(-f);
        k += dk;
        if (dk.norm() <= 1e-14 * std::max(1.0, k.norm())) break;
      }
    }
    kappa[s] = k;
    for (int i = 0; i < m; ++i) {
      const double e = segment_shortening(r[i], seg.length, k, path, seg.disks) - b(i);
      sq += e * e;
    }
    // u = kappa (-sin phi, cos phi, 0) for a bend towards (cos phi, sin phi).
    out[s].u = Vec3(-k.y(), k.x(), 0.0);
  }
  if (misfit) *misfit = std::sqrt(sq);
}

namespace {

// The closed form has no residual system: extract() computes the answer and its summary.
class CcProblem final : public detail::ModelProblem {
 public:
  explicit CcProblem(const CcModel& model) : model_(model) {}
  void bind(const ModelInput& input) { input_ = &input; }

  bvp::ParameterizedSystem* system() override { return nullptr; }
  bvp::NewtonSolver& newton() override { return newton_; }
  void cold_guess(Eigen::VectorXd& x) override { x.resize(0); }
  void rest_state(Eigen::VectorXd& x) override { x.resize(0); }
  bool warm_guess(const Solution&, Eigen::VectorXd&) override { return false; }
  void extract(const Eigen::VectorXd&, bool, Solution& solution) override;
  double max_curvature() const override { return max_curvature_; }

 private:
  const CcModel& model_;
  const ModelInput* input_ = nullptr;  // the input of the solve under way (bind to extract)
  std::vector<CcArc> arcs_;            // the arcs of the last extract (reused memory)
  double max_curvature_ = -1.0;
  bvp::NewtonSolver newton_;
};

class CcWorkspace final : public ModelWorkspace {
 public:
  explicit CcWorkspace(const CcModel& owner) : ModelWorkspace(owner), problem(owner) {}
  CcProblem problem;
};

void CcProblem::extract(const Eigen::VectorXd&, bool, Solution& solution) {
  const ModelInput& input = *input_;
  const Robot& robot = model_.robot();
  const TendonRouting& routing = model_.routing();
  const Effects& effects = model_.effects();
  double misfit = 0.0;
  model_.arcs(input, arcs_, &misfit);
  const std::vector<CcArc>& a = arcs_;
  max_curvature_ = 0.0;
  for (const CcArc& arc : a) max_curvature_ = std::max(max_curvature_, arc.u.norm());

  solution.disk_frames.reserve(routing.disk_count());
  solution.disk_frames.push_back(Frame{});
  // Disks are equally spaced along a segment, so one SE(3) step per segment, composed n times,
  // gives every disk frame (the last one lands at the segment end to rounding).
  Frame current;
  for (std::size_t s = 0; s < robot.segments.size(); ++s) {
    const Segment& seg = robot.segments[s];
    const double ds = seg.length / seg.disks;
    const Frame step = lie::exp_se3(a[s].u * ds, a[s].v * ds);
    for (int j = 0; j < seg.disks; ++j) {
      current = current * step;
      solution.disk_frames.push_back(current);
    }
  }

  // Tendon displacements of the solved shape (what the base actuators see).
  solution.tendon_displacements.assign(routing.tendons.size(), 0.0);
  for (const RoutedTendon& t : routing.tendons) {
    double d = 0.0;
    for (int s = 0; s <= t.segment; ++s) {
      const Segment& seg = robot.segments[s];
      const Eigen::Vector2d k(a[s].u.y(), -a[s].u.x());
      // Axial strain shortens every tendon with the backbone.
      d += segment_shortening(t.r, seg.length, k, effects.tendon_path, seg.disks) +
           seg.length * (1.0 - a[s].v.z());
    }
    if (input.actuation.convention == Actuation::DisplacementConvention::PerSegment) {
      const Segment& seg = robot.segments[t.segment];
      const Eigen::Vector2d k(a[t.segment].u.y(), -a[t.segment].u.x());
      d = segment_shortening(t.r, seg.length, k, effects.tendon_path, seg.disks) +
          seg.length * (1.0 - a[t.segment].v.z());
    }
    solution.tendon_displacements[t.index] = d;
  }
  if (input.actuation.kind == Actuation::Kind::Tensions) solution.tensions = input.actuation.values;

  solution.unknowns.resize(3 * static_cast<Eigen::Index>(a.size()));
  for (std::size_t s = 0; s < a.size(); ++s) solution.unknowns.segment<3>(3 * s) = a[s].u;

  SolverSummary& sum = solution.summary;
  sum.termination = TerminationType::Converged;
  // The least-squares misfit of over-determined displacements (m) is the physical residual.
  sum.message = "closed form";
  sum.physical_residual = misfit;
  sum.residual_norm = 0.0;
  sum.unknowns = static_cast<int>(solution.unknowns.size());
  // CC prescribes its arcs (geometry, or tendon statics without any external load): it has no
  // reduced stiffness to examine, so it does not decide; VC gives the verdict for the same input.
  solution.stability.method = "kinematic model";  // short: no allocation on the hot path
}

}  // namespace

std::unique_ptr<ModelWorkspace> CcModel::make_workspace() const { return std::make_unique<CcWorkspace>(*this); }

detail::ModelProblem& CcModel::bind(ModelWorkspace& workspace, const ModelInput& input, const SolverOptions&) const {
  CcProblem& problem = static_cast<CcWorkspace&>(workspace).problem;
  problem.bind(input);
  return problem;
}


}  // namespace tdcr
