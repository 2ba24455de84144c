// Private to models/: the contact completion of the shooting models (VCref, VC; docs/contact.md):
// after a converged solve, the pairs its answer penetrates join the contact candidates and the
// contact system (the model's residual system with the candidates' force unknowns after its own
// and their complementarity rows, physics/contact_law.hpp) is solved from the answer, until no
// pair is penetrated. The lumped models have their own (lumped_contact.cpp: structured steps).
#pragma once

#include <vector>

#include <Eigen/Core>

#include "physics/contact_law.hpp"
#include "tdcr/bvp/continuation.hpp"
#include "tdcr/bvp/newton_solver.hpp"
#include "tdcr/models/model_problem.hpp"

namespace tdcr::detail {

// What a model gives the completion.
class ContactHost {
 public:
  virtual ~ContactHost() = default;
  // The bound input's obstacles, the robot's contact surfaces, the law and the candidates.
  virtual const std::vector<Obstacle>& contact_obstacles() const = 0;
  virtual const contact::Surfaces& contact_surfaces() const = 0;
  virtual contact::Law& contact_law() = 0;
  virtual std::vector<contact::Candidate>& contact_candidates() = 0;
  // The candidates changed (the system's size and pattern follow them).
  virtual void contact_candidates_changed() = 0;
  // The system whose unknowns are the model's followed by the candidates' forces, its solver.
  virtual bvp::ParameterizedSystem& contact_system() = 0;
  virtual bvp::NewtonSolver& contact_newton() = 0;
  // The disk frames 0..N at unknowns y (false if they cannot be computed); the candidates'
  // forces are y's last entries.
  virtual bool contact_frames(const Eigen::VectorXd& y, std::vector<Frame>& frames) = 0;
  // The unloaded robot with every candidate's force 0 (the system's parameter is 0).
  virtual void contact_rest(Eigen::VectorXd& y) = 0;
  // The disks' arc lengths 0..N (the straight robot at rest: disk j at s_j e_z).
  virtual const std::vector<double>& contact_disk_s() const = 0;
  // Total disks N and robot length L (the candidates' margin 0.1 L / N).
  virtual int contact_disks() const = 0;
  virtual double contact_length() const = 0;
};

// ModelProblem::complete() of a model with contact: the rounds of candidates and contact solves
// from the answer y (see docs/contact.md, "VCref and VC").
ModelProblem::Completion complete_contacts(ContactHost& host, Eigen::VectorXd& y, const bvp::NewtonOptions& options,
                                           SolverSummary& summary);

// The candidates of a previous answer's contacts (its forces as their guess): what a warm start
// begins with.
void warm_contacts(const Solution& previous, int disks, int obstacles, double force_scale,
                   std::vector<contact::Candidate>& candidates);

}  // namespace tdcr::detail
