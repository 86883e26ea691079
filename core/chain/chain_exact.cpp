#include "core/chain/chain_exact.hpp"

#include <algorithm>
#include <cmath>

#include "core/run/error.hpp"

namespace granular {

ChainExactSolution::ChainExactSolution(const std::vector<double>& b, const std::vector<double>& k,
                                       bool periodic) {
  const int N = static_cast<int>(b.size());
  const int C = static_cast<int>(k.size());
  if (C != (periodic ? N : N + 1))
    throw InputError("exact chain solution: contact count does not match the boundary");
  M_ = Eigen::MatrixXd::Zero(N, N);
  K_ = Eigen::MatrixXd::Zero(N, N);
  for (int i = 0; i < N; ++i) M_(i, i) = b[i];
  // Contact c between left bead l and right bead r adds the stiffness k_c to both
  // diagonals (negative) and couples them (positive); walls are not degrees of freedom.
  for (int c = 0; c < C; ++c) {
    const int l = c == 0 ? (periodic ? N - 1 : -1) : c - 1;
    const int r = c == N ? -1 : c;
    if (l >= 0) K_(l, l) -= k[c];
    if (r >= 0) K_(r, r) -= k[c];
    if (l >= 0 && r >= 0) K_(l, r) += k[c], K_(r, l) += k[c];
  }
  if (!periodic) {
    // Between walls -K is tridiagonal, and so is A = M^{-1/2} (-K) M^{-1/2}: its symmetric
    // tridiagonal eigensolver skips the dense reduction (several times faster at N ~ 1000).
    // With A y = w^2 y and y^T y = 1, s = M^{-1/2} y has s^T M s = 1.
    Eigen::VectorXd diag(N), off(std::max(N - 1, 0)), scale(N);
    for (int i = 0; i < N; ++i) scale(i) = 1.0 / std::sqrt(b[i]), diag(i) = -K_(i, i) / b[i];
    for (int i = 0; i + 1 < N; ++i) off(i) = -K_(i, i + 1) * scale(i) * scale(i + 1);
    Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> es;
    es.computeFromTridiagonal(diag, off, Eigen::ComputeEigenvectors);
    if (es.info() != Eigen::Success) throw PhysicsError("exact chain solution: eigensolver failed");
    S_ = scale.asDiagonal() * es.eigenvectors();
    omega_ = es.eigenvalues().cwiseMax(0.0).cwiseSqrt();
    return;
  }
  Eigen::GeneralizedSelfAdjointEigenSolver<Eigen::MatrixXd> es(-K_, M_);
  if (es.info() != Eigen::Success) throw PhysicsError("exact chain solution: eigensolver failed");
  // Eigen normalizes the generalized eigenvectors so that s^T M s = 1.
  S_ = es.eigenvectors();
  omega_ = es.eigenvalues().cwiseMax(0.0).cwiseSqrt();  // the rigid mode can come out -1e-16
}

void ChainExactSolution::set_initial(const Eigen::VectorXd& u0, const Eigen::VectorXd& v0) {
  z0_ = S_.transpose() * (M_ * u0);
  z0dot_ = S_.transpose() * (M_ * v0);
}

void ChainExactSolution::state(double t, Eigen::VectorXd& u, Eigen::VectorXd& v) const {
  const int n = static_cast<int>(omega_.size());
  Eigen::VectorXd zu(n), zv(n);
  for (int m = 0; m < n; ++m) {
    const double w = omega_(m), c = std::cos(w * t), s = std::sin(w * t);
    // sin(w t)/w -> t for the rigid-body mode of a periodic ring.
    const double sinc = w * t > 1e-8 ? s / w : t;
    zu(m) = c * z0_(m) + sinc * z0dot_(m);
    zv(m) = -w * s * z0_(m) + c * z0dot_(m);
  }
  u = S_ * zu;
  v = S_ * zv;
}

double ChainExactSolution::energy(const Eigen::VectorXd& u, const Eigen::VectorXd& v) const {
  return 0.5 * v.dot(M_ * v) - 0.5 * u.dot(K_ * u);
}

}  // namespace granular
