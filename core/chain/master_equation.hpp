// The master equation d e/dt = Q e for normalized band energies (docs/model_chains.md §5):
// fitting the transfer matrix Q from ensemble-averaged standing-wave runs by the two
// procedures of the spec, and its forward solution by the matrix exponential.
#pragma once
#include <Eigen/Dense>
#include <vector>

namespace granular {

// Ensemble-averaged normalized band energies of the runs that agitate one band each:
// series[s] is B x T (band r, sample i) for the run that started in band s; times[i] is
// the time of sample i (times[0] = 0).
struct BandSeries {
  std::vector<double> times;
  std::vector<Eigen::MatrixXd> series;
};

struct FitWindow {
  int first = 2, last = 18;  // sample indices, inclusive
};

// Procedure 1 (non-linear, longer window): decay (1 - y1) exp(-z1 t) + y1 gives
// Q_ss = -z1 (1 - y1); rise y2 (1 - exp(-z2 t)) gives Q_rs = y2 z2.
Eigen::MatrixXd fit_transfer_matrix_nonlinear(const BandSeries& data, FitWindow w);
// Procedure 2 (linear, short window): 1 - x1 t gives Q_ss = -x1; x2 t gives Q_rs = x2
// (least squares through the origin of the deviation from the initial state).
Eigen::MatrixXd fit_transfer_matrix_linear(const BandSeries& data, FitWindow w);

// Q with each diagonal entry replaced by minus the sum of its column's gains, so that
// d/dt sum_r e_r = 0 exactly. Procedure 1 fits every entry independently and does not
// conserve energy by itself; its forward predictions use this balanced form.
Eigen::MatrixXd balance_columns(const Eigen::MatrixXd& Q);

// Procedure 3 (global): all of Q at once, from every tone experiment over the window (the
// whole horizon by default), by least squares on the band energies in integral form,
// e_s(t_i) - e_s(t_0) = Q integral_{t_0}^{t_i} e_s dt (trapezoid rule), under the constraints
// of a physical transfer matrix: off-diagonal rates >= 0 and columns summing to zero (each
// diagonal entry is minus its column's gains: energy is conserved by construction). Solved
// by accelerated projected gradient (FISTA) on the off-diagonal entries; deterministic.
// With `trapped`, band r also holds a fraction f_r of its initial energy that never leaves
// (weak localization), fitted jointly by alternating with Q:
// e(t) = f∘e0 + expm(Q t) (e0 - f∘e0).
struct GlobalFit {
  Eigen::MatrixXd Q;
  Eigen::VectorXd trapped;  // f_r, zeros without trapping
  int iterations = 0;       // projected-gradient iterations, all rounds
  double rms_residual = 0;  // of the integral-form equations
};
GlobalFit fit_transfer_matrix_global(const BandSeries& data, FitWindow w, bool trapped);

// e(t_i) = expm(Q t_i) e0 for every time. On a uniform grid (t_i = i dt) one propagator
// expm(Q dt) is applied step by step: O(B^2) per time instead of a matrix exponential.
Eigen::MatrixXd solve_master_equation(const Eigen::MatrixXd& Q, const Eigen::VectorXd& e0,
                                      const std::vector<double>& times);
// The trapped-fraction model: f∘e0 + expm(Q t_i) (e0 - f∘e0).
Eigen::MatrixXd solve_master_equation_trapped(const Eigen::MatrixXd& Q, const Eigen::VectorXd& f,
                                              const Eigen::VectorXd& e0,
                                              const std::vector<double>& times);

// Single-curve fits, exposed for tests: least-squares (y, z) of the model on (t, e).
struct ExpFit {
  double y = 0, z = 0, residual = 0;
};
ExpFit fit_decay(const std::vector<double>& t, const std::vector<double>& e);
ExpFit fit_rise(const std::vector<double>& t, const std::vector<double>& e);

}  // namespace granular
