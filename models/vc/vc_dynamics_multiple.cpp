// Multiple shooting of a Cosserat dynamics step (vc_dynamics_mesh.hpp, MultipleShooting): VC with
// short time steps, and VCref, whose chords make each disk's load depend on its neighbours.
#include <utility>

#include "tdcr/core/lie.hpp"
#include "tdcr/models/tendon_physics.hpp"
#include "vc/vc_dynamics_mesh.hpp"

namespace tdcr::vc::dyn {

namespace {

constexpr int kNode = 18;  // p, theta, n, m, q, w

int node_offset(int j) { return 6 + kNode * (j - 1); }

}  // namespace

MultipleShooting::MultipleShooting(VcWorkspace::Impl& W, const ShotData& d, bool chords, bool remove_normal,
                                   double velocity, double rate)
    : W_(W), d_(d), chords_(chords), remove_normal_(remove_normal), velocity_(velocity), rate_(rate) {
  length_ = W.model->robot().total_length();
  disks_ = static_cast<int>(d.mesh->intervals.size());
  n_ = 6 + kNode * (disks_ - 1);
  rbar_.assign(disks_ - 1, Mat3::Identity());
  ends_.assign(disks_, State::Zero());
  frames_.assign(disks_ + 1, Frame{});
  // Rows of inner disk j (block j - 1) read nodes j - 1 and j, and with chords node j + 1's pose;
  // the tip rows read node N - 1.
  std::vector<std::pair<int, int>> entries;
  const auto node_cols = [&](int j, int count, std::vector<int>& cols) {
    if (j == 0) {
      for (int c = 0; c < 6; ++c) cols.push_back(c);
      return;
    }
    for (int c = 0; c < count; ++c) cols.push_back(node_offset(j) + c);
  };
  for (int j = 1; j <= disks_; ++j) {
    std::vector<int> cols;
    node_cols(j - 1, kNode, cols);
    const bool tip = j == disks_;
    if (!tip) node_cols(j, kNode, cols);
    if (!tip && chords_ && j + 1 < disks_) node_cols(j + 1, 6, cols);
    const int r0 = tip ? kNode * (disks_ - 1) : kNode * (j - 1);
    const int rows = tip ? 6 : kNode;
    for (int r = 0; r < rows; ++r)
      for (const int c : cols) entries.emplace_back(r0 + r, c);
  }
  pattern_ = bvp::SparsityPattern::from_triplets(n_, n_, entries);
}

void MultipleShooting::node_state(const Eigen::Ref<const Eigen::VectorXd>& x, int j, State& y) const {
  y.setZero();
  if (j == 0) {
    Eigen::Map<Mat3>(y.data() + 3).setIdentity();
    y.segment<6>(12) = x.head<6>();
    return;
  }
  const int o = node_offset(j);
  y.segment<3>(0) = x.segment<3>(o);
  Eigen::Map<Mat3>(y.data() + 3) = rbar_[j - 1] * lie::exp_so3(x.segment<3>(o + 3));
  y.segment<12>(12) = x.segment<12>(o + 6);
}

bool MultipleShooting::residual(const Eigen::Ref<const Eigen::VectorXd>& x, Eigen::Ref<Eigen::VectorXd> f) {
  ++shots;
  last_x = x;
  last_ok = false;
  const Mesh& M = *d_.mesh;
  State y;
  for (int j = 0; j < disks_; ++j) {
    node_state(x, j, y);
    frames_[j] = Frame{Eigen::Map<const Mat3>(y.data() + 3), y.head<3>()};
    if (!integrate_interval(W_, d_, M.intervals[j], y)) return false;
    ends_[j] = y;
  }
  frames_[disks_] = Frame{Eigen::Map<const Mat3>(ends_[disks_ - 1].data() + 3), ends_[disks_ - 1].head<3>()};
  const TendonRouting& rt = W_.model->routing();
  // The tensions acting now (a displacement-driven tendon's is set per evaluation, not bound).
  tensions_.resize(W_.loads.full_tensions().size());
  for (std::size_t k = 0; k < tensions_.size(); ++k) tensions_[k] = W_.loads.tension(static_cast<int>(k));
  const std::vector<double>& T = tensions_;
  for (int j = 1; j <= disks_; ++j) {
    State& e = ends_[j - 1];
    if (chords_) {
      const tendon::DiskWrench w = tendon::disk_wrench(j, frames_.data(), rt, T.data(), remove_normal_);
      e.segment<3>(12) -= w.force;
      e.segment<3>(15) -= w.moment;
    }
    if (!disk_loads(W_, d_, M.intervals[j - 1].segment, j, e.data())) return false;
    if (j == disks_) {
      Eigen::Ref<Eigen::VectorXd> r = f.segment(kNode * (disks_ - 1), 6);
      r = e.segment<6>(12);
      if (W_.loads.has_tip_wrench()) {
        r.head<3>() -= W_.loads.tip_force();
        r.tail<3>() -= W_.loads.tip_moment();
      }
      continue;
    }
    node_state(x, j, y);
    const Eigen::Map<const Mat3> Re(e.data() + 3), Rn(y.data() + 3);
    Eigen::Ref<Eigen::VectorXd> r = f.segment(kNode * (j - 1), kNode);
    r.segment<3>(0) = e.head<3>() - y.head<3>();
    const Mat3 D = Rn.transpose() * Re;
    r.segment<3>(3) = 0.5 * Vec3(D(2, 1) - D(1, 2), D(0, 2) - D(2, 0), D(1, 0) - D(0, 1));
    r.segment<12>(6) = e.segment<12>(12) - y.segment<12>(12);
  }
  last_ok = f.allFinite();
  return last_ok;
}

void MultipleShooting::residual_scale(Eigen::Ref<Eigen::VectorXd> s) const {
  s.head<3>().setConstant(1.0 / force_);
  s.segment<3>(3).setConstant(1.0 / moment_);
  for (int j = 1; j < disks_; ++j) {
    const int o = node_offset(j);
    s.segment<3>(o).setConstant(1.0 / length_);
    s.segment<3>(o + 3).setConstant(1.0);
    s.segment<3>(o + 6).setConstant(1.0 / force_);
    s.segment<3>(o + 9).setConstant(1.0 / moment_);
    s.segment<3>(o + 12).setConstant(1.0 / velocity_);
    s.segment<3>(o + 15).setConstant(1.0 / rate_);
  }
}

void MultipleShooting::from_nodes(const Vec6& base, const StateList& nodes, Eigen::VectorXd& x) {
  x.resize(n_);
  x.head<6>() = base;
  for (int j = 1; j < disks_; ++j) {
    const State& y = nodes[j - 1];
    const int o = node_offset(j);
    rbar_[j - 1] = lie::nearest_rotation(Eigen::Map<const Mat3>(y.data() + 3));
    x.segment<3>(o) = y.head<3>();
    x.segment<3>(o + 3).setZero();
    x.segment<12>(o + 6) = y.segment<12>(12);
  }
}

void MultipleShooting::rebase(Eigen::VectorXd& x) {
  for (int j = 1; j < disks_; ++j) {
    const int o = node_offset(j);
    rbar_[j - 1] = lie::nearest_rotation(rbar_[j - 1] * lie::exp_so3(x.segment<3>(o + 3)));
    x.segment<3>(o + 3).setZero();
  }
  last_ok = false;  // the same x now means other rotations
}

}  // namespace tdcr::vc::dyn
