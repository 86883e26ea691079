// Scene `hysteretic_collision`: head-on collisions with the hysteretic, adhesive,
// elasto-plastic law for several adhesion stiffnesses kc: force against overlap traces the
// triangle loops (load on k1, unload on k2, adhesive branch -kc delta); restitution and
// whether the pair stays stuck together are reported per kc.
#include <Kokkos_Core.hpp>
#include <algorithm>
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

struct HystereticSetup {
  HystereticNormal::Params law;  // k1, k2 and gamma_n; kc per collision
  std::vector<double> kc;        // adhesive stiffnesses, a collision each
  double density = 0, d1 = 0, d2 = 0, speed = 0;
  long resolution = 2000;
};

HystereticSetup read_setup(const SceneFile& scene) {
  HystereticSetup c;
  c.law = read_hysteretic_branches(scene);
  c.kc = scene.reals("contact.kc");
  c.density = scene.real("particles.density");
  c.d1 = scene.real("particles.diameter_1"), c.d2 = scene.real("particles.diameter_2");
  c.speed = scene.real("collision.impact_speed");
  c.resolution = scene.integer("collision.steps_per_contact", 2000);
  for (double kc : c.kc) scene.require(kc >= 0, "contact.kc", "must not be negative");
  scene.require(c.speed > 0, "collision.impact_speed", "must be positive");
  scene.require(c.density > 0, "particles.density", "must be positive");
  scene.require(c.d1 > 0, "particles.diameter_1", "must be positive");
  scene.require(c.d2 > 0, "particles.diameter_2", "must be positive");
  scene.require(c.resolution >= 50 && c.resolution <= 10000000, "collision.steps_per_contact",
                "must lie in [50, 1e7] (every step of a collision is recorded)");
  scene.reject_unknown_keys();
  return c;
}

// One collision of the sweep: its adhesion stiffness, the outcome and the series.
struct HystereticCase {
  double kc_over_k2 = 0, restitution = 0, max_overlap = 0;
  bool separated = false;
  std::vector<double> t, overlap, force;  // every step
};

// A collision per kc, each resolved by `resolution` steps of the stiffest branch's duration.
std::vector<HystereticCase> collide_all(const HystereticSetup& c) {
  const double m1 = c.density * M_PI / 6 * c.d1 * c.d1 * c.d1,
               m2 = c.density * M_PI / 6 * c.d2 * c.d2 * c.d2;
  const double m = m1 * m2 / (m1 + m2);
  std::vector<HystereticCase> cases;
  const double k1 = c.law.k1, k2 = c.law.k2;
  for (double kc : c.kc) {
    ContactModel<HystereticNormal> model{HystereticNormal::uniform(k1, k2, kc, c.law.gn), {}, {}};
    CollisionSetup s;
    s.radius1 = 0.5 * c.d1, s.radius2 = 0.5 * c.d2, s.density = c.density, s.speed = c.speed,
    s.record = true;
    s.dt = M_PI * std::sqrt(m / std::max(k2, kc)) / c.resolution;
    CollisionResult r = collide_head_on<Kokkos::DefaultExecutionSpace>(model, s);
    HystereticCase k;
    k.kc_over_k2 = kc / k2;
    k.separated = r.duration > 0;
    k.restitution = k.separated ? r.restitution : 0.0;
    k.max_overlap = *std::max_element(r.delta.begin(), r.delta.end());
    k.t = std::move(r.t), k.overlap = std::move(r.delta), k.force = std::move(r.force);
    std::cout << "kc/k2 = " << k.kc_over_k2 << ": "
              << (k.separated ? "separated" : "stuck together") << ", restitution " << k.restitution
              << "\n";
    cases.push_back(std::move(k));
  }
  return cases;
}

// Each case's series in results.h5 and its outcome in the summary.
void write_cases(SceneOutput& output, const HystereticSetup& c,
                 const std::vector<HystereticCase>& cases) {
  H5Writer& h5 = output.h5();
  Json list = Json::array();
  for (size_t n = 0; n < cases.size(); ++n) {
    const HystereticCase& k = cases[n];
    Json j = Json::object();
    j["kc_over_k2"] = k.kc_over_k2;
    j["separated"] = k.separated;
    j["restitution"] = k.restitution;
    j["restitution_no_adhesion_closed_form"] = std::sqrt(c.law.k1 / c.law.k2);
    j["max_overlap"] = k.max_overlap;
    list.push(j);
    const std::string g = "/collisions/case_" + std::to_string(n);
    write_quantity(h5, g + "/time", k.t, "us");
    write_quantity(h5, g + "/overlap", k.overlap, "mm");
    write_quantity(h5, g + "/normal_force", k.force, "N");
    h5.attribute(g, "kc_over_k2", k.kc_over_k2);
  }
  h5.attribute("/", "k1", c.law.k1);
  h5.attribute("/", "k2", c.law.k2);
  output.summary()["cases"] = list;
}

}  // namespace

void run_hysteretic_collision(const SceneFile& scene, const RunOptions& opts) {
  const HystereticSetup c = read_setup(scene);
  if (!begin_outputs(opts)) return;
  SceneOutput output(scene, opts, "hysteretic_collision");
  write_cases(output, c, collide_all(c));
  output.finish();
}

}  // namespace granular
