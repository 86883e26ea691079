// Exact solution of the linearized chain M u'' = K u (docs/model_chains.md §1) from the
// generalized symmetric eigenproblem (-K) s = w^2 M s with M-orthonormal modes. It is the
// accuracy reference for time stepping.
#pragma once
#include <Eigen/Dense>
#include <vector>

namespace granular {

class ChainExactSolution {
 public:
  // masses b (N), linearized contact stiffnesses k (C = N + 1 fixed walls, C = N periodic,
  // contact c joining bead c-1 and bead c).
  ChainExactSolution(const std::vector<double>& b, const std::vector<double>& k, bool periodic);

  const Eigen::VectorXd& omega() const { return omega_; }  // ascending
  const Eigen::MatrixXd& modes() const { return S_; }      // columns, s^T M s = 1
  const Eigen::MatrixXd& mass() const { return M_; }
  const Eigen::MatrixXd& stiffness() const { return K_; }  // K (negative semidefinite)

  // Sets the initial state; state(t) then evaluates the closed form at any t.
  void set_initial(const Eigen::VectorXd& u0, const Eigen::VectorXd& v0);
  void state(double t, Eigen::VectorXd& u, Eigen::VectorXd& v) const;
  // Linearized total energy 1/2 v.M v - 1/2 u.K u.
  double energy(const Eigen::VectorXd& u, const Eigen::VectorXd& v) const;

 private:
  Eigen::MatrixXd M_, K_, S_;
  Eigen::VectorXd omega_, z0_, z0dot_;
};

}  // namespace granular
