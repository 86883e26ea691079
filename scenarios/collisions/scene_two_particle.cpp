// Scene `two_particle_linear`: head-on collisions over impact speeds and mass ratios,
// measured contact duration and restitution next to the closed forms of docs/model_dem.md §2.1.
#include <Kokkos_Core.hpp>
#include <cmath>
#include <iostream>

#include "core/io/dataset_units.hpp"
#include "core/io/output.hpp"
#include "scenarios/collisions/two_particle.hpp"
#include "scenarios/common/scene_output.hpp"
#include "scenarios/scene_registry.hpp"

namespace granular {

void run_two_particle_linear(const SceneFile& scene, const RunOptions& opts) {
  const double kn = scene.real("contact.kn"), gn = scene.real("contact.gamma_n");
  const FrictionlessLinear model{LinearNormal::uniform(kn, gn), {}, {}};
  const LinearNormal& normal = model.normal;
  const double density = scene.real("particles.density");
  const double d1 = scene.real("particles.diameter");
  const auto partners = scene.reals("particles.partner_diameters");
  const auto speeds = scene.reals("collisions.impact_speeds");
  const long resolution = scene.integer("collisions.steps_per_contact", 1000);
  scene.require(kn > 0, "contact.kn", "must be positive");
  scene.require(gn >= 0, "contact.gamma_n", "must not be negative");
  scene.require(density > 0, "particles.density", "must be positive");
  scene.require(d1 > 0, "particles.diameter", "must be positive");
  for (double d : partners) scene.require(d > 0, "particles.partner_diameters", "must be positive");
  for (double v : speeds) scene.require(v > 0, "collisions.impact_speeds", "must be positive");
  scene.require(resolution >= 10 && resolution <= 10000000, "collisions.steps_per_contact",
                "must lie in [10, 1e7] (every step of a collision is recorded)");
  scene.reject_unknown_keys();
  for (double d2 : partners) {  // an overdamped pair never separates: no contact duration
    const double m1 = density * M_PI / 6 * d1 * d1 * d1, m2 = density * M_PI / 6 * d2 * d2 * d2;
    const double tc = normal.contact_duration(m1 * m2 / (m1 + m2));
    scene.require(std::isfinite(tc) && tc > 0, "contact.gamma_n",
                  "overdamps the pair of diameters " + std::to_string(d1) + " and " +
                      std::to_string(d2) + ": lower it, or raise particles.density");
  }

  if (!begin_outputs(opts)) return;
  SceneOutput output(scene, opts, "two_particle_linear");
  H5Writer& h5 = output.h5();
  Json& summary = output.summary();
  Json cases = Json::array();
  std::vector<double> mass_ratio, speed, tc_meas, tc_closed, e_meas, e_closed;
  double worst_tc = 0, worst_e = 0, worst_p = 0;
  int k = 0;
  for (double d2 : partners) {
    for (double v : speeds) {
      CollisionSetup s;
      s.radius1 = 0.5 * d1, s.radius2 = 0.5 * d2;
      s.density = density;
      s.speed = v;
      s.record = true;
      const double m1 = density * M_PI / 6 * d1 * d1 * d1, m2 = density * M_PI / 6 * d2 * d2 * d2;
      const double m_red = m1 * m2 / (m1 + m2);
      s.dt = normal.contact_duration(m_red) / resolution;
      const auto r = collide_head_on<Kokkos::DefaultExecutionSpace>(model, s);
      const double tc = normal.contact_duration(m_red), e = normal.restitution(m_red);
      const double dp =
          std::fabs(r.momentum_after - r.momentum_before) / std::fabs(r.momentum_before);
      Json c = Json::object();
      c["diameter_1"] = d1, c["diameter_2"] = d2, c["mass_ratio_m2_m1"] = m2 / m1;
      c["impact_speed"] = v, c["dt"] = s.dt;
      c["contact_duration"] = r.duration, c["contact_duration_closed_form"] = tc;
      c["contact_duration_rel_error"] = r.duration / tc - 1;
      c["restitution"] = r.restitution, c["restitution_closed_form"] = e;
      c["restitution_rel_error"] = r.restitution / e - 1;
      c["momentum_rel_change"] = dp;
      cases.push(c);
      worst_tc = std::max(worst_tc, std::fabs(r.duration / tc - 1));
      worst_e = std::max(worst_e, std::fabs(r.restitution / e - 1));
      worst_p = std::max(worst_p, dp);
      mass_ratio.push_back(m2 / m1), speed.push_back(v);
      tc_meas.push_back(r.duration), tc_closed.push_back(tc);
      e_meas.push_back(r.restitution), e_closed.push_back(e);
      const std::string g = "/collisions/case_" + std::to_string(k++);
      write_quantity(h5, g + "/time", r.t, "us");
      write_quantity(h5, g + "/overlap", r.delta, "mm");
      write_quantity(h5, g + "/normal_force", r.force, "N");
      h5.attribute(g, "mass_ratio", m2 / m1);
      h5.attribute(g, "impact_speed", v);
      h5.attribute(g, "contact_duration_closed_form", tc);
      std::cout << "m2/m1 = " << m2 / m1 << "  v = " << v << "  t_c = " << r.duration
                << " (closed form " << tc << ")  e = " << r.restitution << " (closed form " << e
                << ")\n";
    }
  }
  write_quantity(h5, "/table/mass_ratio", mass_ratio, "1");
  write_quantity(h5, "/table/impact_speed", speed, "mm us-1");
  write_quantity(h5, "/table/contact_duration", tc_meas, "us");
  write_quantity(h5, "/table/contact_duration_closed_form", tc_closed, "us");
  write_quantity(h5, "/table/restitution", e_meas, "1");
  write_quantity(h5, "/table/restitution_closed_form", e_closed, "1");
  summary["cases"] = cases;
  summary["max_rel_error_contact_duration"] = worst_tc;
  summary["max_rel_error_restitution"] = worst_e;
  summary["max_rel_momentum_change"] = worst_p;
  output.finish();
}

}  // namespace granular
