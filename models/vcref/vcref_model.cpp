// VCref: Cosserat rod per subsegment with discrete tendon disk forces, solved by multiple
// shooting with a block-tridiagonal sparse Jacobian (see tdcr/models/vcref.hpp).
#include "tdcr/models/vcref.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <stdexcept>
#include <vector>

#include "common/load_continuation.hpp"
#include "common/model_factories.hpp"
#include "common/newton_summary.hpp"
#include "tdcr/bvp/integrator.hpp"
#include "tdcr/bvp/newton_solver.hpp"
#include "tdcr/bvp/residual_system.hpp"
#include "tdcr/core/error.hpp"
#include "tdcr/core/lie.hpp"
#include "tdcr/models/cosserat_rod.hpp"
#include "tdcr/models/tendon_physics.hpp"

namespace tdcr {

using cosserat::State;

// Everything a solve needs that is decided once from the scene.
struct VcrefModel::Data {
  int N = 0;                       // total disks (disk N = tip)
  int size = 0;                    // unknowns = residuals
  TendonRouting routing;           // all tendons (outputs)
  TendonRouting active;            // only tendons with nonzero tension (physics)
  std::vector<double> tensions;    // by global index
  std::vector<char> tendon_at;     // disk j receives a tendon wrench
  std::vector<char> pass_through;  // some active tendon passes (does not end at) disk j
  std::vector<Vec3> disk_weight;   // disk_mass * g per disk (only if disk_weight)
  bool any_disk_weight = false;
  bool arc_guess = true;           // VcrefOptions::initial_guess
  bool tip_wrench = false;
  bool remove_normal = true;
  Vec3 tip_force = Vec3::Zero();
  Vec3 tip_moment = Vec3::Zero();
  cosserat::Section section;
  double length = 0.0;             // robot length L
  double force_scale = 1.0;        // F_s (N)
  Eigen::VectorXd fscale, uscale;  // residual and unknown scales
  Eigen::VectorXd fd_scale;        // finite-difference step scale per unknown
  bvp::SparsityPattern pattern;
  // Cold-start rule (vcref.hpp, VcrefOptions::load_threshold): decided once.
  double load_parameter = 0.0;         // L^2 (|W| + |F_tip|) / EI
  double compression_parameter = 0.0;  // L^2 max(0, -e_z . (F_tip + W)) / EI
  bool from_rest = false;              // a cold solve loads the robot from rest
  double first_step = 0.0;             // its first load step (0: the continuation default)

  // Index of component k (0..11: p, w, n, m) of unknown block b (block 0 holds n, m only).
  int col(int b, int k) const { return b == 0 ? k - 6 : 6 + 12 * (b - 1) + k; }
  // Index of residual component r of block j = 1..N (tip block: r = 6..11 only).
  int row(int j, int r) const { return j == N ? 12 * (N - 1) + (r - 6) : 12 * (j - 1) + r; }
};

namespace {

constexpr double kFdStep = 1e-7;  // forward-difference step, relative to the unknown's scale

// The multiple-shooting residual system; owns the mutable memory of a solve. Its parameter is
// the load factor (continuation).
class VcrefSystem final : public bvp::ParameterizedSystem {
 public:
  VcrefSystem(const VcrefModel::Data& d, const Scene& scene)
      : d_(d),
        integrator_(bvp::make_integrator(scene.solver)),
        rod_(d.section),
        rbar_(d.N + 1, Mat3::Identity()),
        frames_(d.N + 1),
        end_(d.N + 1, State::Zero()),
        saved_end_(d.N + 1, State::Zero()),
        saved_frames_(d.N + 1),
        tension_(d.tensions) {
    xc_.resize(d.size);
    fc_.resize(d.size);
    fp_.resize(d.size);
    xw_.resize(d.size);
    fd_rel_ = kFdStep;
    if (scene.solver.integrator == IntegratorKind::Cvode)  // adaptive steps: noise ~ rtol
      fd_rel_ = std::max(kFdStep, std::sqrt(scene.solver.cvode_rtol));
    frames_[0] = Frame{};
  }

  int size() const override { return d_.size; }
  const bvp::SparsityPattern* sparsity() const override { return &d_.pattern; }
  bool has_jacobian() const override { return true; }
  void residual_scale(Eigen::Ref<Eigen::VectorXd> s) const override { s = d_.fscale; }
  void unknown_scale(Eigen::Ref<Eigen::VectorXd> s) const override { s = d_.uscale; }

  bool residual(const Eigen::Ref<const Eigen::VectorXd>& x, Eigen::Ref<Eigen::VectorXd> f) override {
    valid_ = false;
    if (!evaluate(x, f)) return false;
    xc_ = x;
    fc_ = f;
    valid_ = true;
    return true;
  }

  bool sparse_jacobian(const Eigen::Ref<const Eigen::VectorXd>& x, const Eigen::Ref<const Eigen::VectorXd>&,
                       double* values) override {
    if (!valid_ || std::memcmp(xc_.data(), x.data(), sizeof(double) * d_.size) != 0) {
      valid_ = false;
      if (!evaluate(x, fc_)) return false;
      xc_ = x;
      valid_ = true;
    }
    ++jacobians_;
    const int N = d_.N;
    xw_ = x;
    bool ok = true;
    for (int k = 0; k < 12 && ok; ++k) {
      for (int g = 0; g < 3 && ok; ++g) {
        bool any = false;
        // Perturb component k of every block b = g mod 3 and redo what depends on it.
        for (int b = g; b < N; b += 3) {
          if (b == 0 && k < 6) continue;
          any = true;
          const int c = d_.col(b, k);
          const double h = k < 6 ? fd_rel_ * d_.fd_scale[c] : fd_rel_ * std::max(std::abs(x[c]), d_.fd_scale[c]);
          xw_[c] = x[c] + h;
          saved_frames_[b] = frames_[b];
          saved_end_[b + 1] = end_[b + 1];
          if (b >= 1 && k < 6) set_frame(b, xw_);
          if (k < 3) {
            // The free rod is translation invariant: the end state moves with the start.
            end_[b + 1][k] += h;
          } else if (!integrate(b + 1, xw_)) {
            ok = false;
          }
          if (b + 1 == N) {
            saved_frames_[N] = frames_[N];
            frames_[N] = cosserat::frame_of(end_[N].data());
          }
        }
        if (!any) continue;
        if (ok) {
          for (int b = g; b < N; b += 3) {
            if (b == 0 && k < 6) continue;
            for (int j = std::max(1, b - 1); j <= std::min(N, b + 1); ++j) block(j, xw_, fp_.data() + d_.row(j, j == N ? 6 : 0));
            const int c = d_.col(b, k);
            const double h = xw_[c] - x[c];
            for (int e = d_.pattern.col_ptr[c]; e < d_.pattern.col_ptr[c + 1]; ++e) {
              const int r = d_.pattern.row_idx[e];
              values[e] = (fp_[r] - fc_[r]) / h;
            }
          }
        }
        // Restore.
        for (int b = g; b < N; b += 3) {
          if (b == 0 && k < 6) continue;
          const int c = d_.col(b, k);
          xw_[c] = x[c];
          frames_[b] = saved_frames_[b];
          end_[b + 1] = saved_end_[b + 1];
          if (b + 1 == N) frames_[N] = saved_frames_[N];
        }
      }
    }
    return ok;
  }

  // F(x) into f; fills frames_ and end_. False if an interval cannot be integrated.
  bool evaluate(const Eigen::Ref<const Eigen::VectorXd>& x, Eigen::Ref<Eigen::VectorXd> f) {
    const int N = d_.N;
    for (int j = 1; j < N; ++j) set_frame(j, x);
    for (int j = 1; j <= N; ++j)
      if (!integrate(j, x)) return false;
    frames_[N] = cosserat::frame_of(end_[N].data());
    for (int j = 1; j <= N; ++j) block(j, x, f.data() + d_.row(j, j == N ? 6 : 0));
    return f.allFinite();
  }

  // Frame of disk j from its unknowns: p_j and R_j = Rbar_j exp(w_j).
  void set_frame(int j, const Eigen::Ref<const Eigen::VectorXd>& x) {
    const int c = d_.col(j, 0);
    frames_[j].p = x.segment<3>(c);
    frames_[j].R = rbar_[j] * lie::exp_so3(x.segment<3>(c + 3));
  }

  // Integrate interval j (disk j-1 -> disk j) from disk j-1's frame and wrench into end_[j].
  bool integrate(int j, const Eigen::Ref<const Eigen::VectorXd>& x) {
    const int c = d_.col(j - 1, 6);
    State& y = end_[j];
    y = cosserat::make_state(frames_[j - 1], x.segment<3>(c), x.segment<3>(c + 3));
    const double s0 = d_.routing.disk_s[j - 1], s1 = d_.routing.disk_s[j];
    return integrator_->integrate(rod_, s0, s1, y.data());
  }

  // Residual block j (12 values, or 6 at the tip) from frames_, end_ and x.
  void block(int j, const Eigen::Ref<const Eigen::VectorXd>& x, double* out) const {
    const int N = d_.N;
    const State& e = end_[j];
    Vec3 F = cosserat::force(e.data());
    Vec3 M = cosserat::moment(e.data());
    if (d_.tendon_at[j]) {
      const tendon::DiskWrench w = tendon::disk_wrench(j, frames_.data(), d_.active, tension_.data(), d_.remove_normal);
      F -= w.force;
      M -= w.moment;
    }
    if (d_.any_disk_weight) F -= load_ * d_.disk_weight[j];
    Eigen::Map<Vec3> o0(out), o1(out + 3);
    if (j < N) {
      const int c = d_.col(j, 0);
      Eigen::Map<Vec3> o2(out + 6), o3(out + 9);
      o0 = x.segment<3>(c) - cosserat::position(e.data());
      o1 = lie::vee(cosserat::rotation(e.data()).transpose() * frames_[j].R);
      o2 = F - x.segment<3>(c + 6);
      o3 = M - x.segment<3>(c + 9);
    } else {
      if (d_.tip_wrench) {
        F -= load_ * d_.tip_force;
        M -= load_ * d_.tip_moment;
      }
      o0 = F;
      o1 = M;
    }
  }

  void set_parameter(double lambda) override { set_load_factor(lambda); }
  // A converged step: fold its rotation increments into the reference rotations.
  void accept_step(Eigen::VectorXd& x) override { rebase(x); }

  // Scale every load (tensions, tip wrench, weights) by `factor` (continuation).
  void set_load_factor(double factor) {
    load_ = factor;
    for (std::size_t k = 0; k < tension_.size(); ++k) tension_[k] = factor * d_.tensions[k];
    cosserat::Section s = d_.section;
    s.weight *= factor;
    rod_ = cosserat::FreeRod(s);
    valid_ = false;
  }

  // Initial guess: disk poses on the constant-curvature arcs of the tendon moments (paper
  // Eq. 8 with u = sum T_k (e_z x r_k) / EI per segment, the CC model's statics) or, with
  // `arcs` false, the straight robot; wrenches from the statics of that shape (backward pass of
  // the disk equilibria, loads times load_). Rbar_j = R_j, w_j = 0.
  void shape_guess(Eigen::VectorXd& x, bool arcs) {
    const int N = d_.N;
    x.setZero(d_.size);
    frames_[0] = Frame{};
    rbar_[0].setIdentity();
    for (int j = 1; j <= N; ++j) {
      const int seg = d_.routing.disk_segment[j];
      const double l = d_.routing.disk_s[j] - d_.routing.disk_s[j - 1];
      Vec3 u = Vec3::Zero();
      if (arcs)
        for (const RoutedTendon& t : d_.active.tendons)
          if (t.segment >= seg) u += tension_[t.index] * Vec3::UnitZ().cross(t.r);
      u = d_.section.inv_kbt.cwiseProduct(u);
      frames_[j] = frames_[j - 1] * lie::exp_se3(u * l, Vec3::UnitZ() * l);
      rbar_[j] = frames_[j].R;
    }
    Vec3 n = Vec3::Zero(), m = Vec3::Zero();  // wrench just distal of disk j
    const Vec3 w = rod_weight();
    for (int j = N; j >= 1; --j) {
      // Disk j: n(s_j-) = n(s_j+) + F_j.
      if (d_.tendon_at[j]) {
        const tendon::DiskWrench dw = tendon::disk_wrench(j, frames_.data(), d_.active, tension_.data(), d_.remove_normal);
        n += dw.force;
        m += dw.moment;
      }
      if (d_.any_disk_weight) n += load_ * d_.disk_weight[j];
      if (j == N && d_.tip_wrench) {
        n += load_ * d_.tip_force;
        m += load_ * d_.tip_moment;
      }
      // Interval j, chord approximation: n' = -w, m' = -p' x n.
      const double l = d_.routing.disk_s[j] - d_.routing.disk_s[j - 1];
      const Vec3 dp = frames_[j].p - frames_[j - 1].p;
      m += dp.cross(n + 0.5 * w * l);
      n += w * l;
      if (j - 1 >= 1) x.segment<3>(d_.col(j - 1, 0)) = frames_[j - 1].p;
      x.segment<3>(d_.col(j - 1, 6)) = n;
      x.segment<3>(d_.col(j - 1, 9)) = m;
    }
    valid_ = false;
  }
  void straight_guess(Eigen::VectorXd& x) { shape_guess(x, d_.arc_guess); }

  // Warm start from a previous solution of the same discretisation.
  bool warm_guess(const Solution& prev, Eigen::VectorXd& x) {
    const int N = d_.N;
    if (prev.unknowns.size() != d_.size || static_cast<int>(prev.disk_frames.size()) != N + 1 ||
        !prev.unknowns.allFinite())
      return false;
    x = prev.unknowns;
    for (int j = 1; j < N; ++j) {
      rbar_[j] = lie::nearest_rotation(prev.disk_frames[j].R);
      x.segment<3>(d_.col(j, 3)).setZero();
    }
    valid_ = false;
    return true;
  }

  // Fold the rotation corrections into the reference rotations: R_j = Rbar_j, w_j = 0.
  void rebase(Eigen::VectorXd& x) {
    for (int j = 1; j < d_.N; ++j) {
      const int c = d_.col(j, 3);
      rbar_[j] = rbar_[j] * lie::exp_so3(x.segment<3>(c));
      x.segment<3>(c).setZero();
    }
    valid_ = false;
  }

  Vec3 rod_weight() const { return d_.section.gravity ? Vec3(load_ * d_.section.weight) : Vec3::Zero(); }

  // Largest rotation mismatch angle (rad) between integrated and unknown disk rotations at the
  // last evaluation: a root of vee(skew(.)) with a mismatch near pi is spurious.
  double max_mismatch_cosine_violation() const {
    double worst = 1.0;
    for (int j = 1; j < d_.N; ++j) {
      const Mat3 A = cosserat::rotation(end_[j].data()).transpose() * frames_[j].R;
      worst = std::min(worst, 0.5 * (A.trace() - 1.0));
    }
    return worst;
  }

  const std::vector<Frame>& frames() const { return frames_; }
  const std::vector<State>& ends() const { return end_; }
  std::string integrator_name() const { return integrator_->name(); }
  int jacobians() const { return jacobians_; }

 private:
  const VcrefModel::Data& d_;
  std::unique_ptr<bvp::Integrator> integrator_;
  cosserat::FreeRod rod_;
  std::vector<Mat3> rbar_;
  std::vector<Frame> frames_;
  std::vector<State> end_, saved_end_;
  std::vector<Frame> saved_frames_;
  std::vector<double> tension_;
  double load_ = 1.0;
  double fd_rel_ = kFdStep;
  Eigen::VectorXd xc_, fc_, fp_, xw_;
  bool valid_ = false;
  int jacobians_ = 0;
};

class VcrefWorkspace final : public LegacyWorkspace {
 public:
  VcrefWorkspace(const VcrefModel::Data& d, const Scene& scene) : system(d, scene) {}
  VcrefSystem system;
  bvp::NewtonSolver newton;
};

}  // namespace

VcrefModel::VcrefModel(const Scene& scene, const VcrefOptions& options) : scene_(scene), options_(options) {
  scene_.validate();
  if (scene_.actuation.kind != Actuation::Kind::Tensions)
    throw InputError("actuation.kind", "displacements", "the VCref model takes tendon tensions");
  if (!(options_.load_threshold > 0.0))
    throw InputError("vcref.load_threshold", format_value(options_.load_threshold), "must be positive");
  if (!(options_.compression_threshold > 0.0))
    throw InputError("vcref.compression_threshold", format_value(options_.compression_threshold), "must be positive");
  auto d = std::make_shared<Data>();
  const Robot& robot = scene_.robot;
  const SceneEffects e = scene_.active_effects();
  d->routing = TendonRouting::from(robot);
  d->N = robot.total_disks();
  const int N = d->N;
  d->size = 6 + 12 * (N - 1);
  d->tensions = scene_.actuation.values;
  d->active = d->routing;
  d->active.tendons.clear();
  for (const RoutedTendon& t : d->routing.tendons)
    if (d->tensions[t.index] != 0.0) d->active.tendons.push_back(t);
  d->tendon_at.assign(N + 1, 0);
  d->pass_through.assign(N + 1, 0);
  for (const RoutedTendon& t : d->active.tendons)
    for (int j = 1; j <= t.end_disk; ++j) {
      d->tendon_at[j] = 1;
      if (j < t.end_disk) d->pass_through[j] = 1;
    }
  d->remove_normal = e.disk_normal_force_removed;
  d->arc_guess = options_.initial_guess == VcrefOptions::InitialGuess::ConstantCurvature;
  d->tip_wrench = e.tip_wrench;
  d->tip_force = scene_.loads.tip_force;
  d->tip_moment = scene_.loads.tip_moment;
  d->section = cosserat::Section::from(scene_);
  d->length = robot.total_length();
  d->any_disk_weight = e.disk_weight;
  d->disk_weight.assign(N + 1, Vec3::Zero());
  double weight = 0.0;
  if (e.disk_weight)
    for (int j = 1; j <= N; ++j) {
      d->disk_weight[j] = robot.segments[d->routing.disk_segment[j]].disk_mass * scene_.loads.gravity;
      weight += d->disk_weight[j].norm();
    }
  if (e.backbone_weight) weight += d->section.weight.norm() * d->length;
  Vec3 weight_vec = Vec3::Zero();  // total weight (N, base frame)
  for (int j = 1; j <= N; ++j) weight_vec += d->disk_weight[j];
  if (e.backbone_weight) weight_vec += d->section.weight * d->length;

  // Cold-start rule (see vcref.hpp): load parameters of the external loads only (tensions do
  // not buckle the backbone: the tendon chords follow the disks).
  {
    const double EI = robot.backbone.effective_stiffness().EI;
    const double L2 = d->length * d->length;
    const Vec3 F = e.tip_wrench ? scene_.loads.tip_force : Vec3::Zero();
    d->load_parameter = L2 * (weight_vec.norm() + F.norm()) / EI;
    d->compression_parameter = L2 * std::max(0.0, -(F + weight_vec).z()) / EI;
    const double a = d->load_parameter / options_.load_threshold;
    const double b = d->compression_parameter / options_.compression_threshold;
    const double worst = std::max(a, b);  // > 1: beyond a threshold
    d->from_rest = worst > 1.0;
    d->first_step = d->from_rest ? 1.0 / worst : 0.0;
  }

  // Scales (see header).
  double tsum = 0.0;
  for (double t : d->tensions) tsum += std::abs(t);
  const double L = d->length;
  d->force_scale = tsum + scene_.loads.tip_force.norm() + scene_.loads.tip_moment.norm() / L + weight + 1e-3;
  const double Fs = d->force_scale;
  d->fscale.resize(d->size);
  d->uscale.resize(d->size);
  const double comp_scale[4] = {1.0 / L, 1.0, 1.0 / Fs, 1.0 / (Fs * L)};
  for (int j = 1; j <= N; ++j)
    for (int r = (j == N ? 6 : 0); r < 12; ++r) d->fscale[d->row(j, r)] = comp_scale[r / 3];
  for (int b = 0; b < N; ++b)
    for (int k = (b == 0 ? 6 : 0); k < 12; ++k) d->uscale[d->col(b, k)] = comp_scale[k / 3];
  // Finite-difference steps: the tendon chord directions vary on the scale of the shortest
  // interval l_min (positions) and l_min / r_max (rotations), not on the robot's scale; steps
  // relative to those keep the second-order error of the forward differences at ~1e-7 even
  // with 1000 disks per segment (a step relative to L gives 2e-4 there and stalls Newton).
  double l_min = L, r_max = 0.0;
  for (int j = 1; j <= N; ++j) l_min = std::min(l_min, d->routing.disk_s[j] - d->routing.disk_s[j - 1]);
  for (const RoutedTendon& t : d->active.tendons) r_max = std::max(r_max, t.r.norm());
  const double fd_comp[4] = {l_min, r_max > 0.0 ? std::min(1.0, l_min / r_max) : 1.0, Fs, Fs * L};
  d->fd_scale.resize(d->size);
  for (int b = 0; b < N; ++b)
    for (int k = (b == 0 ? 6 : 0); k < 12; ++k) d->fd_scale[d->col(b, k)] = fd_comp[k / 3];

  // Block-tridiagonal pattern: row block j depends on x_{j-1} (through the end state of
  // interval j), on x_j, and on the pose of x_{j+1} (equilibrium rows, only if a tendon passes
  // disk j). Row block N-1 depends on x_{N-1} also through the tip pose.
  // Built column by column in CSC order directly (rows ascend block by block).
  bvp::SparsityPattern& P = d->pattern;
  P.rows = P.cols = d->size;
  P.col_ptr.assign(1, 0);
  P.col_ptr.reserve(d->size + 1);
  P.row_idx.reserve(static_cast<std::size_t>(N) * 330);
  for (int b = 0; b < N; ++b)
    for (int k = (b == 0 ? 6 : 0); k < 12; ++k) {
      if (b - 1 >= 1 && k < 6 && d->pass_through[b - 1])
        for (int r = 6; r < 12; ++r) P.row_idx.push_back(d->row(b - 1, r));
      if (b >= 1)
        for (int r = 0; r < 12; ++r) P.row_idx.push_back(d->row(b, r));
      for (int r = (b + 1 == N ? 6 : 0); r < 12; ++r) P.row_idx.push_back(d->row(b + 1, r));
      P.col_ptr.push_back(static_cast<int>(P.row_idx.size()));
    }
  if (!P.valid()) throw std::logic_error("VcrefModel: invalid Jacobian pattern");
  data_ = d;
}

int VcrefModel::unknowns() const { return data_->size; }
double VcrefModel::load_parameter() const { return data_->load_parameter; }
double VcrefModel::compression_parameter() const { return data_->compression_parameter; }
bool VcrefModel::loads_from_rest() const { return data_->from_rest; }
int VcrefModel::jacobian_nonzeros() const { return data_->pattern.nnz(); }

std::unique_ptr<LegacyWorkspace> VcrefModel::make_workspace() const {
  return std::make_unique<VcrefWorkspace>(*data_, scene_);
}

Solution VcrefModel::solve(LegacyWorkspace& workspace, const Solution* warm_start) const {
  const auto t0 = std::chrono::steady_clock::now();
  auto* ws = dynamic_cast<VcrefWorkspace*>(&workspace);
  if (!ws) throw InputError("workspace", "", "not a VCref workspace (use VcrefModel::make_workspace)");
  const Data& d = *data_;
  VcrefSystem& sys = ws->system;
  const bvp::NewtonOptions opts = bvp::NewtonOptions::from(scene_.solver);

  Solution sol;
  sol.model = "vcref";
  SolverSummary& sum = sol.summary;
  sum.unknowns = d.size;
  sum.integrator = sys.integrator_name();

  Eigen::VectorXd x;
  sys.set_load_factor(1.0);
  const bool warm = warm_start && sys.warm_guess(*warm_start, x);
  if (!warm && d.from_rest && scene_.solver.continuation) {
    // Cold solve under large external loads: load the robot from rest (exact at factor 0), the
    // first step within the thresholds. A direct Newton solve can converge to another
    // equilibrium (vcref.hpp).
    char why[160];
    std::snprintf(why, sizeof why,
                  "loaded from rest: L^2 (|W| + |F_tip|) / EI = %.3g, compression parameter %.3g (thresholds %g, %g)",
                  d.load_parameter, d.compression_parameter, options_.load_threshold, options_.compression_threshold);
    sys.set_load_factor(0.0);
    sys.shape_guess(x, false);
    detail::continue_loads(ws->newton, sys, x, opts, scene_.solver, sum, d.first_step, why);
  } else {
    if (!warm) sys.straight_guess(x);
    bvp::NewtonResult r = ws->newton.solve(sys, x, opts);
    detail::copy_newton_result(r, sum);
    if (!r.converged() && scene_.solver.continuation) {
      // Load continuation from the straight, unloaded robot (exact at factor 0).
      sys.set_load_factor(0.0);
      sys.shape_guess(x, false);
      detail::continue_loads(ws->newton, sys, x, opts, scene_.solver, sum, d.first_step);
    }
  }

  // Final state at the returned iterate (frames, interval ends).
  Eigen::VectorXd f(d.size);
  const bool evaluated = sys.residual(x, f);

  // Outputs.
  const int N = d.N;
  if (evaluated) {
    sol.disk_frames = sys.frames();
    sol.disk_frames[N].R = lie::nearest_rotation(sol.disk_frames[N].R);
    sol.backbone.resize(N + 1);
    sol.backbone[0] = BackboneSample{0.0, Frame{}, x.segment<3>(0), x.segment<3>(3)};
    for (int j = 1; j <= N; ++j) {
      const double* e = sys.ends()[j].data();
      sol.backbone[j] = BackboneSample{d.routing.disk_s[j], sol.disk_frames[j], cosserat::force(e), cosserat::moment(e)};
    }
    sol.tendon_displacements =
        tendon::chord_displacements(sys.frames(), d.routing, scene_.actuation.convention);
  } else {
    sol.disk_frames.assign(N + 1, Frame{});
  }
  sol.tensions = d.tensions;
  sol.unknowns = x;
  sum.solve_time_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  return sol;
}

bvp::JacobianCheck VcrefModel::check_jacobian(LegacyWorkspace& workspace, const Solution* at,
                                              double perturbation) const {
  auto* ws = dynamic_cast<VcrefWorkspace*>(&workspace);
  if (!ws) throw InputError("workspace", "", "not a VCref workspace (use VcrefModel::make_workspace)");
  VcrefSystem& sys = ws->system;
  sys.set_load_factor(1.0);
  Eigen::VectorXd x;
  if (!(at && sys.warm_guess(*at, x))) sys.straight_guess(x);
  for (int i = 0; i < x.size(); ++i) x[i] += perturbation * std::sin(1.0 + i) / data_->uscale[i];
  return bvp::check_jacobian(sys, x);
}

namespace detail {
std::unique_ptr<LegacyStaticModel> make_legacy_vcref_model(const Scene& scene) { return std::make_unique<VcrefModel>(scene); }
}  // namespace detail

}  // namespace tdcr
