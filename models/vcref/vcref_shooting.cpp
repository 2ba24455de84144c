// VCref's multiple-shooting problem: the chart of the disk unknowns, the residual blocks (tip
// and disk equilibria, pose continuity), scales and finite-difference steps.
#include "vcref/vcref_shooting.hpp"

#include <algorithm>
#include <cmath>
#include <cstring>

#include "physics/tendon_path.hpp"
#include "tdcr/core/lie.hpp"
#include "tdcr/models/tendon_physics.hpp"

namespace tdcr {

namespace {
constexpr double kFdStep = 1e-7;  // forward-difference step, relative to the unknown's scale
Eigen::Map<Vec3> out(double* r) { return Eigen::Map<Vec3>(r); }
bool same_bits(const Frame& a, const Frame& b) {
  return std::memcmp(a.R.data(), b.R.data(), 9 * sizeof(double)) == 0 &&
         std::memcmp(a.p.data(), b.p.data(), 3 * sizeof(double)) == 0;
}
}  // namespace

VcrefShooting::VcrefShooting(const VcrefModel::Data& d)
    : d_(d),
      tendon_at_(d.N + 1, 0),
      passes_(d.pass_through),
      section_(d.section),
      rod_(d.section),
      rbar_(d.N, Mat3::Identity()),
      frames_(d.N + 1),
      wrench_memo_(d.N + 1) {}

void VcrefShooting::bind(const ModelInput& input, const SolverOptions& options) {
  const TendonRouting& routing = *d_.routing;
  load_.bind(*d_.robot, routing, input);
  bind_contact(input);
  damping_ = 0.0;  // a snap switches it off again; a new input never starts damped
  active_ = routing;
  active_.tendons.clear();
  for (const RoutedTendon& t : routing.tendons)
    if (load_.full_tensions()[t.index] != 0.0) active_.tendons.push_back(t);
  std::fill(tendon_at_.begin(), tendon_at_.end(), 0);
  std::fill(passes_.begin(), passes_.end(), 0);
  double r_max = 0.0;
  for (const RoutedTendon& t : active_.tendons) {
    r_max = std::max(r_max, physics::max_offset(t));
    for (int j = 1; j <= t.end_disk; ++j) {
      tendon_at_[j] = 1;
      if (j < t.end_disk) passes_[j] = 1;
    }
  }
  const double L = d_.length, Fs = load_.force_scale();
  const double comp[4] = {1.0 / L, 1.0, 1.0 / Fs, 1.0 / (Fs * L)};
  std::copy(comp, comp + 4, comp_scale_);
  // Finite-difference steps on the scales of the unknowns: the Jacobian takes the tendon wrenches,
  // whose chords turn on the much shorter scales of the shortest interval l_min (positions) and
  // l_min / r_max (rotations), through their exact linearisation (begin_linearization). With
  // tendon friction it differentiates them in full, with steps on those short scales (their
  // rounding then grows with the disk count).
  const double l = d_.l_min;
  const double fd[4] = {d_.friction ? l : L, d_.friction && r_max > 0.0 ? std::min(1.0, l / r_max) : 1.0, Fs, Fs * L};
  std::copy(fd, fd + 4, fd_comp_);
  fd_rel_ = kFdStep;
  if (options.integrator == IntegratorKind::Cvode)  // adaptive steps: noise ~ rtol
    fd_rel_ = std::max(kFdStep, std::sqrt(options.cvode_rtol));
  if (d_.friction) chord_.assign(load_.full_tensions().size() * routing.disk_count(), 0.0);
  set_load_factor(1.0);
}

void VcrefShooting::set_driven_tensions(const std::vector<int>& index, const Eigen::VectorXd& T) {
  for (std::size_t i = 0; i < index.size(); ++i) load_.set_fixed_tension(index[i], T[static_cast<Eigen::Index>(i)]);
  set_load_factor(load_.load_factor());
}

void VcrefShooting::set_load_factor(double lambda) {
  load_.set_load_factor(lambda);
  tension_.resize(load_.full_tensions().size());
  for (std::size_t k = 0; k < tension_.size(); ++k) tension_[k] = load_.tension(static_cast<int>(k));
  ++tension_version_;  // invalidates wrench_memo_
  section_ = d_.section;
  section_.gravity = load_.has_backbone_weight();
  section_.weight = load_.backbone_weight();
  rod_ = cosserat::FreeRod(section_);
}

void VcrefShooting::start_state(int k, const double* x, double* y) const {
  using namespace cosserat;
  if (k == 0) {
    position(y).setZero();
    rotation(y).setIdentity();
    force(y) = Eigen::Map<const Vec3>(x);
    moment(y) = Eigen::Map<const Vec3>(x + 3);
    return;
  }
  // The Jacobian perturbs one unknown at a time: most calls repeat the last rotation.
  const Eigen::Map<const Vec3> w(x + 3);
  if (k != chart_node_ || w != chart_w_) {
    chart_node_ = k;
    chart_w_ = w;
    chart_R_ = rbar_[k] * lie::exp_so3(w);
  }
  position(y) = Eigen::Map<const Vec3>(x);
  rotation(y) = chart_R_;
  force(y) = Eigen::Map<const Vec3>(x + 6);
  moment(y) = Eigen::Map<const Vec3>(x + 9);
}

void VcrefShooting::rebase(int k, double* x) {
  if (k == 0) return;
  Eigen::Map<Vec3> w(x + 3);
  rbar_[k] = rbar_[k] * lie::exp_so3(w);
  w.setZero();
  chart_node_ = -1;
}

// Block 0 (tip) reads node N-1 (its pose and, through the last interval's end, everything);
// block b reads nodes b-1 (interval end, pose), b (pose, wrench) and the pose of b+1 in its
// equilibrium rows when a tensioned tendon passes disk b.
std::pair<int, int> VcrefShooting::dependent_rows(int block, int k, int j) const {
  const int N = d_.N;
  if (d_.friction && k > 0 && component(k, j) < 6) {
    // Friction: a disk's tendon tensions follow the poses of every disk up to the next one.
    if (block == 0) return {0, 6};
    if (k == block || k == block - 1) return {0, 12};
    return k <= block + 1 ? std::make_pair(6, 12) : std::make_pair(0, 0);
  }
  if (block == 0) return k == N - 1 ? std::make_pair(0, 6) : std::make_pair(0, 0);
  if (k == block || k == block - 1) return {0, 12};
  if (k == block + 1 && j < 6 && passes_[block]) return {6, 12};
  return {0, 0};
}

// Subtracts the tendon wrench and the disk weight on disk j from F, M; frames_ j-1, j (and
// j+1 if some tendon passes) must be set when a tendon acts on disk j.
void VcrefShooting::subtract_disk_load(int j, Vec3& F, Vec3& M) const {
  if (tendon_at_[j]) {
    tendon::DiskWrench w;
    if (d_.friction) {
      w = tendon::disk_wrench_friction(j, frames_.data(), active_, chord_.data(), d_.remove_normal);
    } else if (linearized_) {
      w = linearized_wrench(j);
    } else {
      // Bit-identical frames give the bit-identical wrench: reuse it.
      WrenchMemo& m = wrench_memo_[j];
      const int read = j < d_.N && passes_[j] ? 3 : 2;
      bool hit = m.version == tension_version_;
      for (int i = 0; hit && i < read; ++i) hit = same_bits(m.frames[i], frames_[j - 1 + i]);
      if (!hit) {
        m.wrench = tendon::disk_wrench(j, frames_.data(), active_, tension_.data(), d_.remove_normal);
        for (int i = 0; i < read; ++i) m.frames[i] = frames_[j - 1 + i];
        m.version = tension_version_;
      }
      w = m.wrench;
    }
    F -= w.force;
    M -= w.moment;
  }
  if (load_.has_disk_weight()) F -= load_.disk_weight(j);
}

void VcrefShooting::subtract_contact(int j, const Frame& frame, Vec3& F, Vec3& M) const {
  for (std::size_t i = 0; i < candidates_.size(); ++i) {
    if (candidates_[i].disk != j) continue;
    const ContactPoint at = contact_at(i, frame);
    const Vec3 f = (candidates_[i].lambda * law_.force_scale) * at.normal;
    F -= f;
    M -= (at.point - frame.p).cross(f);
  }
}

void VcrefShooting::bind_contact(const ModelInput& input) {
  candidates_.clear();
  obstacles_ = input.environment.obstacles;  // allocates only when the obstacles grow
  if (obstacles_.empty()) return;
  const Robot& robot = *d_.robot;
  const TendonRouting& routing = *d_.routing;
  surfaces_.backbone_radius = robot.backbone.outer_radius;
  surfaces_.disk_radius.assign(d_.N + 1, 0.0);
  for (int j = 0; j <= d_.N; ++j) surfaces_.disk_radius[j] = robot.segments[routing.disk_segment[j]].disk_radius;
  law_ = contact::Law{};
  law_.stiffness = input.environment.contact.stiffness;
  law_.force_scale = 1.0 / (d_.section.inv_kbt.x() * d_.length * d_.length);  // EI / L^2
  law_.length_scale = surfaces_.backbone_radius > 0.0 ? surfaces_.backbone_radius : 1e-3 * d_.length;
}

void VcrefShooting::begin_linearization(const bvp::ShootingNodes& nominal) const {
  if (d_.friction) return;
  linearized_ = true;
  nominal_ = nominal;
  for (LinearWrench& l : linear_) l.disk = -1;
}

Frame VcrefShooting::nominal_frame(int k) const {
  return cosserat::frame_of(k < d_.N ? nominal_.start(k) : nominal_.end(d_.N - 1));
}

// The wrench at the nominal frames is tendon::disk_wrench's there (bit for bit the residual's);
// moved frames add D (dp, log(R_nominal^T R)).
tendon::DiskWrench VcrefShooting::linearized_wrench(int j) const {
  const int read = j < d_.N && passes_[j] ? 3 : 2;
  LinearWrench* l = nullptr;
  for (LinearWrench& c : linear_)
    if (c.disk == j) l = &c;
  if (!l) {
    l = &linear_[linear_next_];
    linear_next_ = (linear_next_ + 1) % 4;
    l->disk = j;
    Frame saved[3];
    for (int i = 0; i < read; ++i) {
      saved[i] = frames_[j - 1 + i];
      l->frames[i] = frames_[j - 1 + i] = nominal_frame(j - 1 + i);
    }
    tendon::DiskWrench same_up_to_rounding;
    disk_wrench_derivative(j, frames_.data(), same_up_to_rounding, l->D);
    l->wrench = tendon::disk_wrench(j, frames_.data(), active_, tension_.data(), d_.remove_normal);
    for (int i = 0; i < read; ++i) frames_[j - 1 + i] = saved[i];
  }
  tendon::DiskWrench w = l->wrench;
  for (int i = 0; i < read; ++i) {
    const Frame& now = frames_[j - 1 + i];
    const Frame& was = l->frames[i];
    if (same_bits(now, was)) continue;
    Eigen::Matrix<double, 6, 1> d;
    d.head<3>() = now.p - was.p;
    d.tail<3>() = lie::log_so3(was.R.transpose() * now.R);
    const Eigen::Matrix<double, 6, 1> dw = l->D.middleCols<6>(6 * i) * d;
    w.force += dw.head<3>();
    w.moment += dw.tail<3>();
  }
  return w;
}

void VcrefShooting::friction_frames(int j, const bvp::ShootingNodes& nodes) const {
  const int N = d_.N, last = std::min(j + 1, N);
  for (int k = 0; k <= last; ++k) frames_[k] = cosserat::frame_of(k < N ? nodes.start(k) : nodes.end(N - 1));
  tendon::friction_tensions(frames_.data(), active_, tension_.data(), d_.tendon_friction, chord_.data(), last);
}

void VcrefShooting::boundary(const bvp::ShootingNodes& nodes, double* r) const {
  const int N = d_.N;
  const double* e = nodes.end(N - 1);
  Vec3 F = cosserat::force(e), M = cosserat::moment(e);
  if (d_.friction && tendon_at_[N]) {
    friction_frames(N, nodes);
  } else if (tendon_at_[N]) {
    frames_[N - 1] = cosserat::frame_of(nodes.start(N - 1));
    frames_[N] = cosserat::frame_of(e);
  }
  subtract_disk_load(N, F, M);
  if (!candidates_.empty()) subtract_contact(N, cosserat::frame_of(e), F, M);
  if (load_.has_tip_wrench()) {
    F -= load_.tip_force();
    M -= load_.tip_moment();
  }
  out(r) = F;
  out(r + 3) = M;
}

void VcrefShooting::junction(int j, const bvp::ShootingNodes& nodes, double* r) const {
  const int N = d_.N;
  const double* e = nodes.end(j - 1);
  const double* y = nodes.start(j);
  Vec3 F = cosserat::force(e), M = cosserat::moment(e);
  if (d_.friction && tendon_at_[j]) {
    friction_frames(j, nodes);
  } else if (tendon_at_[j]) {
    frames_[j - 1] = cosserat::frame_of(nodes.start(j - 1));
    frames_[j] = cosserat::frame_of(y);
    if (passes_[j]) frames_[j + 1] = cosserat::frame_of(j + 1 < N ? nodes.start(j + 1) : nodes.end(N - 1));
  }
  subtract_disk_load(j, F, M);
  if (!candidates_.empty()) subtract_contact(j, cosserat::frame_of(y), F, M);
  out(r) = cosserat::position(y) - cosserat::position(e);
  out(r + 3) = lie::vee(cosserat::rotation(e).transpose() * cosserat::rotation(y));
  out(r + 6) = F - cosserat::force(y);
  out(r + 9) = M - cosserat::moment(y);
  if (damping_ > 0.0) {
    // The rows are the gradient of the potential in the disk's position and (world) rotation.
    const double Fs = load_.force_scale(), L = d_.length;
    const Mat3& R = cosserat::rotation(y);
    out(r + 6) += damping_ * (Fs / L) * (cosserat::position(y) - damping_ref_[j].p);
    out(r + 9) += damping_ * (Fs * L) * (R * lie::log_so3(damping_ref_[j].R.transpose() * R));
  }
}

void VcrefShooting::set_damping(const double* x, double rate) {
  damping_ = rate;
  if (rate == 0.0) return;
  damping_ref_.resize(d_.N);  // allocates once per workspace, at its first damped snap
  cosserat::State y;
  for (int k = 1; k < d_.N; ++k) {
    start_state(k, x + 6 + 12 * (k - 1), y.data());
    damping_ref_[k] = cosserat::frame_of(y.data());
  }
}

void VcrefShooting::unknown_scale(int k, double* s) const {
  for (int j = 0; j < unknown_dimension(k); ++j) s[j] = comp_scale_[component(k, j) / 3];
}

void VcrefShooting::block_scale(int block, double* s) const { unknown_scale(block, s); }

// Positions and rotations: absolute steps on the scales above; wrenches: relative to the value.
double VcrefShooting::increment(int k, int j, double value, double, double) const {
  const int c = component(k, j);
  return c < 6 ? fd_rel_ * fd_comp_[c / 3] : fd_rel_ * std::max(std::abs(value), fd_comp_[c / 3]);
}

}  // namespace tdcr
