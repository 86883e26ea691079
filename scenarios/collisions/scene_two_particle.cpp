// Scene `two_particle_linear`: head-on collisions over impact speeds and mass ratios,
// measured contact duration and restitution next to the closed forms of docs/model_dem.md §2.1.
#include <Kokkos_Core.hpp>
#include <cmath>
#include <iostream>
#include <string>
#include <utility>
#include <vector>

#include "core/io/dataset_units.hpp"
#include "core/io/output.hpp"
#include "scenarios/collisions/two_particle.hpp"
#include "scenarios/common/contact_config.hpp"
#include "scenarios/common/scene_output.hpp"
#include "scenarios/scene_registry.hpp"

namespace granular {

namespace {

struct TwoParticleSetup {
  double kn = 0, gn = 0, density = 0, d1 = 0;
  std::vector<double> partners, speeds;
  long resolution = 1000;
};

TwoParticleSetup read_setup(const SceneFile& scene) {
  TwoParticleSetup c;
  const LinearNormal::Params law = read_linear_normal(scene, std::nullopt);  // gamma_n required
  c.kn = law.kn, c.gn = law.gn;
  c.density = scene.real("particles.density");
  c.d1 = scene.real("particles.diameter");
  c.partners = scene.reals("particles.partner_diameters");
  c.speeds = scene.reals("collisions.impact_speeds");
  c.resolution = scene.integer("collisions.steps_per_contact", 1000);
  scene.require(c.density > 0, "particles.density", "must be positive");
  scene.require(c.d1 > 0, "particles.diameter", "must be positive");
  for (double d : c.partners)
    scene.require(d > 0, "particles.partner_diameters", "must be positive");
  for (double v : c.speeds) scene.require(v > 0, "collisions.impact_speeds", "must be positive");
  scene.require(c.resolution >= 10 && c.resolution <= 10000000, "collisions.steps_per_contact",
                "must lie in [10, 1e7] (every step of a collision is recorded)");
  scene.reject_unknown_keys();
  const LinearNormal normal = LinearNormal::uniform(c.kn, c.gn);
  for (double d2 : c.partners) {  // an overdamped pair never separates: no contact duration
    const double m1 = c.density * M_PI / 6 * c.d1 * c.d1 * c.d1,
                 m2 = c.density * M_PI / 6 * d2 * d2 * d2;
    const double tc = normal.contact_duration(m1 * m2 / (m1 + m2));
    scene.require(std::isfinite(tc) && tc > 0, "contact.gamma_n",
                  "overdamps the pair of diameters " + std::to_string(c.d1) + " and " +
                      std::to_string(d2) + ": lower it, or raise particles.density");
  }
  return c;
}

// One collision of the sweep, beside the closed forms of its pair.
struct TwoParticleCase {
  double d2 = 0, speed = 0, mass_ratio = 0, dt = 0;
  double tc_closed = 0, e_closed = 0;
  double duration = 0, restitution = 0, momentum_change = 0;  // measured
  std::vector<double> t, overlap, force;                      // the series, every step
};

// Every partner diameter at every speed, each collision resolved by `resolution` steps.
std::vector<TwoParticleCase> collide_all(const TwoParticleSetup& c) {
  const FrictionlessLinear model{LinearNormal::uniform(c.kn, c.gn), {}, {}};
  std::vector<TwoParticleCase> cases;
  for (double d2 : c.partners)
    for (double v : c.speeds) {
      CollisionSetup s;
      s.radius1 = 0.5 * c.d1, s.radius2 = 0.5 * d2;
      s.density = c.density;
      s.speed = v;
      s.record = true;
      const double m1 = c.density * M_PI / 6 * c.d1 * c.d1 * c.d1,
                   m2 = c.density * M_PI / 6 * d2 * d2 * d2;
      const double m_red = m1 * m2 / (m1 + m2);
      s.dt = model.normal.contact_duration(m_red) / c.resolution;
      CollisionResult r = collide_head_on<Kokkos::DefaultExecutionSpace>(model, s);
      TwoParticleCase k;
      k.d2 = d2, k.speed = v, k.mass_ratio = m2 / m1, k.dt = s.dt;
      k.tc_closed = model.normal.contact_duration(m_red),
      k.e_closed = model.normal.restitution(m_red);
      k.duration = r.duration, k.restitution = r.restitution;
      k.momentum_change =
          std::fabs(r.momentum_after - r.momentum_before) / std::fabs(r.momentum_before);
      k.t = std::move(r.t), k.overlap = std::move(r.delta), k.force = std::move(r.force);
      std::cout << "m2/m1 = " << k.mass_ratio << "  v = " << v << "  t_c = " << k.duration
                << " (closed form " << k.tc_closed << ")  e = " << k.restitution << " (closed form "
                << k.e_closed << ")\n";
      cases.push_back(std::move(k));
    }
  return cases;
}

// Each case's series and the table of results.h5; the cases and the largest errors of the
// summary.
void write_cases(SceneOutput& output, double d1, const std::vector<TwoParticleCase>& cases) {
  H5Writer& h5 = output.h5();
  Json list = Json::array();
  std::vector<double> mass_ratio, speed, tc_meas, tc_closed, e_meas, e_closed;
  double worst_tc = 0, worst_e = 0, worst_p = 0;
  for (size_t n = 0; n < cases.size(); ++n) {
    const TwoParticleCase& k = cases[n];
    Json c = Json::object();
    c["diameter_1"] = d1, c["diameter_2"] = k.d2, c["mass_ratio_m2_m1"] = k.mass_ratio;
    c["impact_speed"] = k.speed, c["dt"] = k.dt;
    c["contact_duration"] = k.duration, c["contact_duration_closed_form"] = k.tc_closed;
    c["contact_duration_rel_error"] = k.duration / k.tc_closed - 1;
    c["restitution"] = k.restitution, c["restitution_closed_form"] = k.e_closed;
    c["restitution_rel_error"] = k.restitution / k.e_closed - 1;
    c["momentum_rel_change"] = k.momentum_change;
    list.push(c);
    worst_tc = std::max(worst_tc, std::fabs(k.duration / k.tc_closed - 1));
    worst_e = std::max(worst_e, std::fabs(k.restitution / k.e_closed - 1));
    worst_p = std::max(worst_p, k.momentum_change);
    mass_ratio.push_back(k.mass_ratio), speed.push_back(k.speed);
    tc_meas.push_back(k.duration), tc_closed.push_back(k.tc_closed);
    e_meas.push_back(k.restitution), e_closed.push_back(k.e_closed);
    const std::string g = "/collisions/case_" + std::to_string(n);
    write_quantity(h5, g + "/time", k.t, "us");
    write_quantity(h5, g + "/overlap", k.overlap, "mm");
    write_quantity(h5, g + "/normal_force", k.force, "N");
    h5.attribute(g, "mass_ratio", k.mass_ratio);
    h5.attribute(g, "impact_speed", k.speed);
    h5.attribute(g, "contact_duration_closed_form", k.tc_closed);
  }
  write_quantity(h5, "/table/mass_ratio", mass_ratio, "1");
  write_quantity(h5, "/table/impact_speed", speed, "mm us-1");
  write_quantity(h5, "/table/contact_duration", tc_meas, "us");
  write_quantity(h5, "/table/contact_duration_closed_form", tc_closed, "us");
  write_quantity(h5, "/table/restitution", e_meas, "1");
  write_quantity(h5, "/table/restitution_closed_form", e_closed, "1");
  Json& summary = output.summary();
  summary["cases"] = list;
  summary["max_rel_error_contact_duration"] = worst_tc;
  summary["max_rel_error_restitution"] = worst_e;
  summary["max_rel_momentum_change"] = worst_p;
}

}  // namespace

void run_two_particle_linear(const SceneFile& scene, const RunOptions& opts) {
  const TwoParticleSetup c = read_setup(scene);
  if (!begin_outputs(opts)) return;
  SceneOutput output(scene, opts, "two_particle_linear");
  write_cases(output, c.d1, collide_all(c));
  output.finish();
}

}  // namespace granular
