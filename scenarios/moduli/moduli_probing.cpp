// The host-side helpers of probing: size statistics and mean contact stiffnesses of a
// saved configuration, probing steps for a rate.
#include "scenarios/moduli/moduli_probing.hpp"

#include <algorithm>
#include <cmath>

namespace granular::moduli_study {

SizeStats size_stats(const ConfigState& c) {
  double s1 = 0, s2 = 0, s3 = 0, rho = 0;
  const int n = c.size();
  for (int i = 0; i < n; ++i) {
    const double d = 2 * c.particles.radius[i];
    s1 += d, s2 += d * d, s3 += d * d * d, rho += c.particles.density[i];
  }
  return {s1 / n, rho / n, s2 / s3 * s1 / n};
}

double mean_normal_stiffness(const ConfigState& c, const ContactConfig& cc) {
  if (cc.normal == "linear") return cc.linear.kn;
  if (cc.normal == "hysteretic") return cc.hysteretic.k2;
  const HostParticles& p = c.particles;
  double sum = 0, count = 0;
  for (int i = 0; i < c.size(); ++i)
    for (int j = i + 1; j < c.size(); ++j) {
      const double r[3] = {c.box.min_image(p.x[i] - p.x[j], 0), c.box.min_image(p.y[i] - p.y[j], 1),
                           c.box.min_image(p.z[i] - p.z[j], 2)};
      const double ai = p.radius[i], aj = p.radius[j];
      const double delta = ai + aj - std::sqrt(r[0] * r[0] + r[1] * r[1] + r[2] * r[2]);
      if (delta <= 0) continue;
      const double L = cc.hertz.reduced_radius ? ai * aj / (ai + aj) : ai + aj;
      sum += 1.5 * cc.hertz.K * std::sqrt(L * delta), count += 1;
    }
  return count > 0 ? sum / count : kNaN;
}

double stiffness_ratio(const ContactConfig& cc, double kn_mean, double kt_override) {
  if (cc.tangential != "coulomb") return 0.0;
  if (kt_override >= 0) return kt_override;
  if (cc.coulomb.law == 0) return cc.coulomb.kt / kn_mean;
  // Mindlin spring kt sqrt(L delta) against Hertz 1.5 K sqrt(L delta), the same L.
  return cc.normal == "hertz" ? cc.coulomb.kt / (1.5 * cc.hertz.K) : kNaN;
}

long steps_for(const Setup& s, double amplitude, double base_rate) {
  const double steps = amplitude / (base_rate * s.params.dt);
  // max_strain_steps >= 20 is checked on read, but a variant's own dt rescales it.
  return std::clamp(static_cast<long>(std::ceil(steps)), 20L, std::max(20L, s.max_strain_steps));
}

double rel_change(double a, double b) { return std::fabs(a / b - 1.0); }

}  // namespace granular::moduli_study
