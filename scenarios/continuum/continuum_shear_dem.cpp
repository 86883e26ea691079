// The DEM pure-shear path behind the continuum law's shear validation.
#include "scenarios/continuum/continuum_shear_dem.hpp"

#include <Kokkos_Core.hpp>
#include <cmath>

#include "kernels/dem/dem_system.hpp"
#include "scenarios/common/element_test.hpp"

namespace granular {

DemShearPath run_dem_pure_shear(const DemShearSpec& s) {
  using Model = ContactModel<LinearNormal, CoulombTangential, NoRolling>;
  using System = DemSystem<Kokkos::DefaultExecutionSpace, Model>;
  PeriodicBox box;
  const HostParticles host = random_gas(s.gas, box);
  DemParams params;
  params.dt_key = "shear.dt";
  params.dt = s.dt, params.skin = s.skin, params.max_overlap = s.max_overlap;
  params.damping.translational = s.damping_background;
  params.damping.rotational = s.damping_rotational;
  // Frictionless preparation, as the mu = 0 studies whose fit this path checks.
  const Model prep{LinearNormal::uniform(s.kn, s.gamma_n),
                   CoulombTangential::uniform(s.kt, s.gamma_t, 0.0, 0.0),
                   {}};
  System sys(Particles<Kokkos::DefaultExecutionSpace>::from_host(host), box, prep, params);
  strain_to_phi(sys, s.phi, -s.volumetric_strain_rate / 3.0, 1000, nullptr);
  relax(sys, s.relax_ratio, s.relax_max_steps);
  // Shear with tangential springs from zero, the way the moduli studies probe.
  sys.set_model(Model{LinearNormal::uniform(s.kn, s.gamma_n),
                      CoulombTangential::uniform(s.kt, s.gamma_t, s.mu, s.mu),
                      {}});
  DemShearPath out;
  const PeriodicBox box0 = sys.box();
  auto sample = [&]() {
    const Measurements m = sys.measure();
    sys.check_health(m);
    out.stretch_x.push_back(sys.box().len[0] / box0.len[0]);
    out.stretch_y.push_back(sys.box().len[1] / box0.len[1]);
    out.stretch_z.push_back(sys.box().len[2] / box0.len[2]);
    out.sxx.push_back(m.stress[0]), out.syy.push_back(m.stress[1]), out.szz.push_back(m.stress[2]);
    out.sxy.push_back(m.stress[3]), out.sxz.push_back(m.stress[4]), out.syz.push_back(m.stress[5]);
    out.pressure.push_back(m.pressure), out.z.push_back(m.z_corrected);
    return m;
  };
  const Measurements m0 = sample();
  out.phi = m0.phi, out.z_corrected = m0.z_corrected;
  // Rates of L_x and L_y whose true strains are -rate t and +rate t (isochoric).
  const double per_sample = s.strain / s.samples;
  const long steps = std::max(1L, std::lround(per_sample / (s.strain_rate * s.dt)));
  const double r = std::expm1(-per_sample / steps) / s.dt;
  const double ry = std::expm1(per_sample / steps) / s.dt;
  sys.set_strain_rate(r, ry, 0.0);
  for (int k = 0; k < s.samples; ++k) {
    sys.step(steps);
    sample();
  }
  sys.set_strain_rate(0, 0, 0);
  return out;
}

}  // namespace granular
