// Scene `hysteretic_collision`: head-on collisions with the hysteretic, adhesive,
// elasto-plastic law for several adhesion stiffnesses kc: force against overlap traces the
// triangle loops (load on k1, unload on k2, adhesive branch -kc delta); restitution and
// whether the pair stays stuck together are reported per kc.
#include <Kokkos_Core.hpp>
#include <cmath>
#include <iostream>

#include "core/io/dataset_units.hpp"
#include "core/io/output.hpp"
#include "scenarios/collisions/two_particle.hpp"
#include "scenarios/common/scene_output.hpp"
#include "scenarios/scene_registry.hpp"

namespace granular {

void run_hysteretic_collision(const SceneFile& scene, const RunOptions& opts) {
  const double k2 = scene.real("contact.k2");
  const double k1 = scene.real("contact.k1_over_k2") * k2;
  const auto kc_ratios = scene.reals("contact.kc_over_k2");
  const double gn = scene.real("contact.gamma_n", 0.0);
  const double density = scene.real("particles.density");
  const double d1 = scene.real("particles.diameter_1"), d2 = scene.real("particles.diameter_2");
  const double speed = scene.real("collision.impact_speed");
  const long resolution = scene.integer("collision.steps_per_contact", 2000);
  scene.require(k2 > 0, "contact.k2", "must be positive");
  scene.require(k1 > 0 && k1 <= k2, "contact.k1_over_k2", "must be in (0, 1]");
  for (double r : kc_ratios) scene.require(r >= 0, "contact.kc_over_k2", "must not be negative");
  scene.require(speed > 0, "collision.impact_speed", "must be positive");
  scene.require(density > 0, "particles.density", "must be positive");
  scene.require(d1 > 0, "particles.diameter_1", "must be positive");
  scene.require(d2 > 0, "particles.diameter_2", "must be positive");
  scene.require(resolution >= 50 && resolution <= 10000000, "collision.steps_per_contact",
                "must lie in [50, 1e7] (every step of a collision is recorded)");
  scene.reject_unknown_keys();

  if (!begin_outputs(opts)) return;
  SceneOutput output(scene, opts, "hysteretic_collision");
  H5Writer& h5 = output.h5();
  Json& summary = output.summary();
  Json cases = Json::array();
  const double m1 = density * M_PI / 6 * d1 * d1 * d1, m2 = density * M_PI / 6 * d2 * d2 * d2;
  const double m = m1 * m2 / (m1 + m2);
  int k = 0;
  for (double ratio : kc_ratios) {
    ContactModel<HystereticNormal> model{HystereticNormal::uniform(k1, k2, ratio * k2, gn), {}, {}};
    CollisionSetup s;
    s.radius1 = 0.5 * d1, s.radius2 = 0.5 * d2, s.density = density, s.speed = speed,
    s.record = true;
    s.dt = M_PI * std::sqrt(m / std::max(k2, ratio * k2)) / resolution;
    const auto r = collide_head_on<Kokkos::DefaultExecutionSpace>(model, s);
    const bool separated = r.duration > 0;
    Json c = Json::object();
    c["kc_over_k2"] = ratio;
    c["separated"] = separated;
    c["restitution"] = separated ? r.restitution : 0.0;
    c["restitution_no_adhesion_closed_form"] = std::sqrt(k1 / k2);
    c["max_overlap"] = *std::max_element(r.delta.begin(), r.delta.end());
    cases.push(c);
    const std::string g = "/collisions/case_" + std::to_string(k++);
    write_quantity(h5, g + "/time", r.t, "us");
    write_quantity(h5, g + "/overlap", r.delta, "mm");
    write_quantity(h5, g + "/normal_force", r.force, "N");
    h5.attribute(g, "kc_over_k2", ratio);
    std::cout << "kc/k2 = " << ratio << ": " << (separated ? "separated" : "stuck together")
              << ", restitution " << (separated ? r.restitution : 0.0) << "\n";
  }
  h5.attribute("/", "k1", k1);
  h5.attribute("/", "k2", k2);
  summary["cases"] = cases;
  output.finish();
}

}  // namespace granular
