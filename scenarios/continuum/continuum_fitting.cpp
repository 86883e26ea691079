// Fits of the continuum law to elastic-moduli studies and the isotropic-path validation.
#include "scenarios/continuum/continuum_fitting.hpp"

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <fstream>
#include <sstream>

#include "core/continuum/deformation_paths.hpp"
#include "core/io/output.hpp"
#include "core/run/error.hpp"

namespace granular {

namespace {

// A number stored under "key" in a study's summary.json (the parameters block writes every
// scene value once, so the first match is the one).
double summary_number(const std::string& path, const std::string& key) {
  std::ifstream in(path);
  if (!in) throw InputError("cannot read " + path);
  std::stringstream buf;
  buf << in.rdbuf();
  const std::string text = buf.str(), quoted = "\"" + key + "\":";
  const size_t at = text.find(quoted);
  if (at == std::string::npos) throw InputError(path + " has no parameter " + key);
  return std::strtod(text.c_str() + at + quoted.size(), nullptr);
}

std::string mu_text(double mu) {
  std::ostringstream s;
  s << mu;
  return s.str();
}

// Linear interpolation of y(x) on a monotonic x (either direction); NaN outside.
double interpolate(const std::vector<double>& x, const std::vector<double>& y, double at) {
  for (size_t i = 1; i < x.size(); ++i) {
    const double a = x[i - 1], b = x[i];
    if ((at - a) * (at - b) <= 0 && a != b)
      return y[i - 1] + (y[i] - y[i - 1]) * (at - a) / (b - a);
  }
  return NAN;
}

void finish(BranchError& e) {
  double s2 = 0;
  for (size_t i = 0; i < e.phi.size(); ++i) {
    const double d = e.p_law[i] - e.p_dem[i];
    s2 += d * d;
    e.max_abs = std::max(e.max_abs, std::abs(d));
    e.p_scale = std::max(e.p_scale, e.p_dem[i]);
  }
  e.rms = e.phi.empty() ? 0.0 : std::sqrt(s2 / e.phi.size());
}

// C*(nu) fitted on the unloading branch: the branch the probed configurations lie on.
void fit_coordination(const ModuliData& d, double z_min, ContinuumFit& f) {
  std::vector<double> x, y;
  for (size_t i = d.peak; i < d.prep_phi.size(); ++i)
    if (d.prep_z[i] >= z_min && d.prep_pressure[i] > 0)
      x.push_back(d.prep_phi[i]), y.push_back(d.prep_z[i]);
  if (x.size() < 8) throw InputError(d.name + ": too few jammed points on the unloading branch");
  f.coordination_points = static_cast<int>(x.size());
  const double phi_low = *std::min_element(x.begin(), x.end());
  const double z_low = *std::min_element(y.begin(), y.end());
  auto coordination = [&](const Eigen::VectorXd& p) {
    Eigen::VectorXd r(x.size());
    for (size_t i = 0; i < x.size(); ++i) {
      const double s = std::max(x[i] / p[0] - 1.0, 0.0);
      r[i] = p[1] + p[2] * std::pow(s, p[3]) - y[i];
    }
    return r;
  };
  LeastSquaresOptions oc;
  // nu0 no higher than the loosest jammed point (the law's C* starts there), alpha > 0, and
  // C0 >= z_min: a jammed packing has at least that many contacts per particle (4 with
  // infinite friction in 3D). Without it a branch that stays jammed down to its last point
  // (frictional preparations) trades C0 against nu0 down to C0 = 0, nu0 = 0.58.
  oc.lower = {0.5, z_min, 0.0, 0.05};
  oc.upper = {phi_low, 20.0, 200.0, 3.0};
  f.coordination = levenberg_marquardt(
      coordination, Eigen::Vector4d(phi_low - 0.01, std::max(z_low, z_min), 10.0, 0.5), oc);
  ContinuumConstants& c = f.law;
  c.nu0 = f.coordination.params[0], c.C0 = f.coordination.params[1];
  c.C1 = f.coordination.params[2], c.alpha = f.coordination.params[3];
}

// g3 through the origin: F_v = g3 (C* nu) with the measured C* = Z* of each configuration;
// F_v0 = C0 g3 nu0 derived from it. Returns F_v0's standard error.
double fit_fabric(const ModuliData& d, ContinuumFit& f) {
  ContinuumConstants& c = f.law;
  const int n = static_cast<int>(d.phi.size());
  Eigen::MatrixXd X(n, 1);
  Eigen::VectorXd Fv(n);
  for (int i = 0; i < n; ++i) X(i, 0) = d.z[i] * d.phi[i], Fv[i] = d.fabric[i];
  f.fabric = linear_least_squares(X, Fv);
  c.g3 = f.fabric.params[0];
  c.Fv0 = c.C0 * c.g3 * c.nu0;
  // Independent-error propagation (the C* and fabric fits use different data).
  const auto& ec = f.coordination.std_error;
  const double sFv0 = std::sqrt(std::pow(c.g3 * c.nu0 * ec[1], 2) +
                                std::pow(c.C0 * c.nu0 * f.fabric.std_error[0], 2) +
                                std::pow(c.C0 * c.g3 * ec[0], 2));
  return sFv0;
}

// K linear in the measured fabric, G a power law in it above F_v0.
void fit_bulk_and_shear(const ModuliData& d, ContinuumFit& f) {
  ContinuumConstants& c = f.law;
  const int n = static_cast<int>(d.phi.size());
  Eigen::MatrixXd XK(n, 2);
  Eigen::VectorXd yK(n), yG(n);
  for (int i = 0; i < n; ++i)
    XK(i, 0) = 1, XK(i, 1) = d.fabric[i] - c.Fv0, yK[i] = d.K[i], yG[i] = d.G[i];
  f.bulk = linear_least_squares(XK, yK);
  c.K0 = f.bulk.params[0], c.K1 = f.bulk.params[1];

  // G: power law in the fabric above F_v0; start from the straight line (G2 = 1).
  const LeastSquaresFit g_line = linear_least_squares(XK, yG);
  auto shear = [&](const Eigen::VectorXd& p) {
    Eigen::VectorXd r(n);
    for (int i = 0; i < n; ++i) {
      const double s = std::max(d.fabric[i] - c.Fv0, 0.0);
      r[i] = p[0] + p[1] * std::pow(s, p[2]) - yG[i];
    }
    return r;
  };
  LeastSquaresOptions og;
  og.lower = {-1e12, -1e12, 0.05};
  og.upper = {1e12, 1e12, 3.0};
  f.shear =
      levenberg_marquardt(shear, Eigen::Vector3d(g_line.params[0], g_line.params[1], 1.0), og);
  c.G0 = f.shear.params[0], c.G1 = f.shear.params[1], c.G2 = f.shear.params[2];
}

// The constants with their standard errors, units and whether a bound held them.
std::vector<FittedConstant> constants_table(const ContinuumFit& f, double sFv0) {
  const ContinuumConstants& c = f.law;
  const auto& ec = f.coordination.std_error;
  const auto& cb = f.coordination.at_bound;
  const auto& gb = f.shear.at_bound;
  return {
      {"nu0", c.nu0, ec[0], "-", cb[0]},
      {"C0", c.C0, ec[1], "-", cb[1]},
      {"C1", c.C1, ec[2], "-", cb[2]},
      {"alpha", c.alpha, ec[3], "-", cb[3]},
      {"g3", c.g3, f.fabric.std_error[0], "-", false},
      {"Fv0", c.Fv0, sFv0, "- (derived: C0 g3 nu0)", false},
      {"K0", c.K0, f.bulk.std_error[0], "MPa", false},
      {"K1", c.K1, f.bulk.std_error[1], "MPa", false},
      {"G0", c.G0, f.shear.std_error[0], "MPa", gb[0]},
      {"G1", c.G1, f.shear.std_error[1], "MPa", gb[1]},
      {"G2", c.G2, f.shear.std_error[2], "-", gb[2]},
  };
}

}  // namespace

std::vector<ModuliData> read_moduli_study(const std::string& dir, const std::string& label) {
  H5Reader h5(dir + "/results.h5");
  const double d_mean = 0.5 * (summary_number(dir + "/summary.json", "particles.diameter_min") +
                               summary_number(dir + "/summary.json", "particles.diameter_max"));
  const auto mu = h5.reals("/table/mu_preparation"), phi = h5.reals("/table/phi");
  const auto z = h5.reals("/table/z_corrected"), K = h5.reals("/table/K_star");
  const auto G = h5.reals("/table/G_star"), kn = h5.reals("/table/kn_mean");
  const auto P = h5.reals("/table/pressure_star");
  const auto fxx = h5.reals("/table/fabric_xx"), fyy = h5.reals("/table/fabric_yy"),
             fzz = h5.reals("/table/fabric_zz");
  const auto variant = h5.reals("/preparation/variant"), pphi = h5.reals("/preparation/phi");
  const auto pp = h5.reals("/preparation/pressure"), pz = h5.reals("/preparation/z_corrected");
  // Preparation variants run in the order of the study's friction list, which is also the
  // order in which the table's frictions first appear.
  std::vector<double> mus;
  for (double m : mu)
    if (std::find(mus.begin(), mus.end(), m) == mus.end()) mus.push_back(m);
  std::vector<ModuliData> out(mus.size());
  for (size_t v = 0; v < mus.size(); ++v) {
    ModuliData& d = out[v];
    d.study = dir, d.mu = mus[v], d.d_mean = d_mean;
    d.name = label + " mu=" + mu_text(mus[v]);
    for (size_t r = 0; r < mu.size(); ++r) {
      // Unjammed rows have no moduli (Z* = 0, K* at round-off level).
      if (mu[r] != mus[v] || !(z[r] > 0) || !(K[r] > 0) || !(G[r] > 0)) continue;
      const double scale = kn[r] / d_mean;
      d.phi.push_back(phi[r]), d.z.push_back(z[r]), d.fabric.push_back(fxx[r] + fyy[r] + fzz[r]);
      d.K.push_back(K[r] * scale), d.G.push_back(G[r] * scale);
      d.pressure.push_back(P[r] * scale), d.kn_mean.push_back(kn[r]);
    }
    for (size_t i = 0; i < variant.size(); ++i) {
      if (variant[i] != static_cast<double>(v)) continue;
      d.prep_phi.push_back(pphi[i]), d.prep_pressure.push_back(pp[i]), d.prep_z.push_back(pz[i]);
    }
    if (d.prep_phi.empty() || d.phi.size() < 4)
      throw InputError(dir + ": preparation friction " + mu_text(mus[v]) +
                       " has no preparation series or fewer than 4 jammed configurations");
    d.peak = static_cast<size_t>(std::max_element(d.prep_phi.begin(), d.prep_phi.end()) -
                                 d.prep_phi.begin());
  }
  return out;
}

ContinuumFit fit_continuum_law(const ModuliData& d, double z_min) {
  ContinuumFit f;
  f.z_min = z_min;
  fit_coordination(d, z_min, f);
  const double sFv0 = fit_fabric(d, f);
  fit_bulk_and_shear(d, f);
  ContinuumConstants& c = f.law;
  c.units = "MPa (N/mm^2) for K0, K1, G0, G1; K = K* kn_mean / dbar with dbar = " +
            std::to_string(d.d_mean) + " mm";

  f.constants = constants_table(f, sFv0);
  return f;
}

IsotropicValidation validate_isotropic(const ModuliData& d, const ContinuumConstants& law,
                                       VolumeFractionUpdate update, double step) {
  IsotropicValidation v;
  const double phi_max = d.prep_phi[d.peak];
  const double phi_min = *std::min_element(d.prep_phi.begin() + d.peak, d.prep_phi.end());
  MaterialPoint p(law, law.nu0, update);
  const PathRecord up =
      drive_to_volume_fraction(p, step_increment(PathKind::isotropic, -step), phi_max);
  const PathRecord down =
      drive_to_volume_fraction(p, step_increment(PathKind::isotropic, step), phi_min);
  v.law_phi = up.nu, v.law_p = up.pressure;
  v.law_phi.insert(v.law_phi.end(), down.nu.begin() + 1, down.nu.end());
  v.law_p.insert(v.law_p.end(), down.pressure.begin() + 1, down.pressure.end());
  for (size_t i = 0; i < d.prep_phi.size(); ++i) {
    const bool loading = i < d.peak;
    const double at = d.prep_phi[i];
    if (loading && at < law.nu0) continue;  // the gas below jamming is not the law's domain
    const double pl =
        interpolate(loading ? up.nu : down.nu, loading ? up.pressure : down.pressure, at);
    if (!std::isfinite(pl)) continue;
    BranchError& b = loading ? v.loading : v.unloading;
    b.phi.push_back(at), b.p_dem.push_back(d.prep_pressure[i]), b.p_law.push_back(pl);
  }
  for (size_t i = 0; i < d.phi.size(); ++i) {
    const double pl = interpolate(down.nu, down.pressure, d.phi[i]);
    if (!std::isfinite(pl)) continue;
    v.configurations.phi.push_back(d.phi[i]);
    v.configurations.p_dem.push_back(d.pressure[i]);
    v.configurations.p_law.push_back(pl);
  }
  finish(v.loading), finish(v.unloading), finish(v.configurations);
  return v;
}

}  // namespace granular
