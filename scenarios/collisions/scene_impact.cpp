// Scene `impact`: single-contact verification. A sphere hits a wall or a sphere at rest at
// a list of incidence angles (and a list of speeds for head-on impacts), with any initial
// spin and any pair of materials (Hertz-Mindlin with restitution damping). Each case is
// reported next to its closed form where one exists: elastic Hertz duration, overlap and
// force; gross sliding (tangential impulse mu (1 + e) times the normal one, spin change,
// rebound angle); the restitution against the input one over the speeds, for the chosen
// mapping of e to the damping constant and for the other one.
#include <Kokkos_Core.hpp>
#include <cmath>
#include <iostream>

#include "core/dem/restitution.hpp"
#include "core/io/dataset_units.hpp"
#include "core/io/output.hpp"
#include "core/run/finite.hpp"
#include "scenarios/collisions/impact.hpp"
#include "scenarios/collisions/impact_closed_forms.hpp"
#include "scenarios/common/materials.hpp"
#include "scenarios/common/scene_output.hpp"
#include "scenarios/scene_registry.hpp"

namespace granular {

namespace {

struct ImpactScene {
  MaterialSet materials;
  int sphere = 0, target = 0;
  bool wall = true;
  double radius = 1, target_radius = 1;
  std::vector<double> speeds, angles;
  double oblique_speed = 1;
  double spin = 0;  // about y, in units of v / R (negative: backspin against the motion)
  int steps_per_contact = 400;
  long snapshot_every = 0;  // ParaView time series of each oblique impact (0: none)
};

ImpactScene read_scene(const SceneFile& s) {
  ImpactScene c;
  c.materials = MaterialSet::read(s);
  const std::string target = s.text("impact.target", "wall");
  s.require(target == "wall" || target == "sphere", "impact.target",
            "must be \"wall\" or \"sphere\"");
  c.wall = target == "wall";
  c.sphere = c.materials.at(s, "impact.sphere_material");
  c.target = c.materials.at(s, "impact.target_material");
  c.radius = 0.5 * s.real("impact.diameter");
  c.target_radius = c.wall ? 0.0 : 0.5 * s.real("impact.target_diameter");
  c.speeds = s.reals("impact.speeds");
  c.angles = s.reals("impact.angles_deg", {0.0});
  c.oblique_speed = s.real("impact.oblique_speed", c.speeds.back());
  c.spin = s.real("impact.spin", 0.0);
  c.steps_per_contact = s.small_integer("impact.steps_per_contact", 400);
  c.snapshot_every = s.integer("output.snapshot_every", 0);
  s.require(c.radius > 0, "impact.diameter", "must be positive");
  s.require(c.wall || c.target_radius > 0, "impact.target_diameter", "must be positive");
  for (double v : c.speeds) s.require(v > 0, "impact.speeds", "must be positive");
  s.require(c.oblique_speed > 0, "impact.oblique_speed", "must be positive");
  for (double a : c.angles) s.require(a >= 0 && a < 90, "impact.angles_deg", "must lie in [0, 90)");
  s.require(c.steps_per_contact >= 50, "impact.steps_per_contact", "must be at least 50");
  s.require(c.snapshot_every >= 0, "output.snapshot_every", "must not be negative");
  s.require(c.materials.materials[c.sphere].density > 0, "impact.sphere_material",
            "needs a material with a positive density");
  s.require(c.wall || c.materials.materials[c.target].density > 0, "impact.target_material",
            "needs a material with a positive density");
  s.require(!c.materials.materials[c.sphere].rigid() || !c.materials.materials[c.target].rigid(),
            "impact.target_material", "and the sphere's material are both rigid");
  s.reject_unknown_keys();
  return c;
}

template <class Model>
ImpactResult run_case(const Model& model, const ImpactScene& c, double speed, double angle_deg,
                      bool record, double estar, double rstar, double mstar,
                      SnapshotSeries* snapshots = nullptr) {
  ImpactSetup s;
  s.wall = c.wall, s.wall_material = c.target;
  s.radius1 = c.radius, s.density1 = c.materials.materials[c.sphere].density;
  s.species1 = c.sphere;
  s.radius2 = c.target_radius, s.species2 = c.target;
  s.density2 = c.wall ? 0.0 : c.materials.materials[c.target].density;
  s.speed = speed, s.angle = angle_deg * M_PI / 180.0;
  s.spin[1] = c.spin * speed / c.radius;
  const double vn = speed * std::cos(s.angle);
  s.dt = hertz_closed_form(estar, rstar, mstar, vn).duration / c.steps_per_contact;
  s.dt_hint = "raise impact.steps_per_contact (now " + std::to_string(c.steps_per_contact) + ")";
  s.record = record;
  s.snapshots = snapshots;
  return impact<Kokkos::DefaultExecutionSpace>(model, s);
}

// The pair's reduced quantities, its restitution and friction.
struct ImpactPair {
  double estar = 0, rstar = 0, mstar = 0, e_in = 0, mu = 0;
};
ImpactPair impact_pair(const ImpactScene& c) {
  const MaterialSet& mats = c.materials;
  ImpactPair p;
  p.estar = mats.effective_young(c.sphere, c.target);
  p.rstar = c.wall ? c.radius : c.radius * c.target_radius / (c.radius + c.target_radius);
  const double m1 = mats.materials[c.sphere].density * 4.0 / 3.0 * M_PI * std::pow(c.radius, 3);
  const double m2 =
      c.wall ? 0.0
             : mats.materials[c.target].density * 4.0 / 3.0 * M_PI * std::pow(c.target_radius, 3);
  p.mstar = c.wall ? m1 : m1 * m2 / (m1 + m2);
  p.e_in = mats.restitution(c.sphere, c.target);
  p.mu = mats.tangential ? (c.sphere == c.target ? mats.materials[c.sphere].friction
                                                 : mats.pair(mats.materials[c.sphere].friction,
                                                             mats.materials[c.target].friction))
                         : 0.0;
  return p;
}

// 1. Head-on impacts over the speeds, with both mappings of e to the damping constant.
void speed_sweep(const ImpactScene& c, const ImpactPair& p, H5Writer& h5, Json& summary) {
  const MaterialSet& mats = c.materials;
  const double estar = p.estar, rstar = p.rstar, mstar = p.mstar, e_in = p.e_in;
  Json speeds = Json::array();
  std::vector<double> e_exact, e_common, tc_ratio;
  for (const std::string& mapping :
       {std::string("restitution_exact"), std::string("restitution_common")}) {
    MaterialSet m = mats;
    m.damping = mapping;
    with_material_model(m, [&](const auto& model) {
      for (double v : c.speeds) {
        const ImpactResult r = run_case(model, c, v, 0.0, false, estar, rstar, mstar);
        (mapping == "restitution_exact" ? e_exact : e_common).push_back(r.restitution_normal);
        if (mapping != mats.damping) continue;
        const auto cf = hertz_closed_form(estar, rstar, mstar, v);
        Json j = Json::object();
        j["speed"] = v;
        j["restitution"] = r.restitution_normal;
        j["duration"] = r.duration;
        j["max_overlap"] = r.max_overlap;
        j["max_normal_force"] = r.max_normal_force;
        j["elastic_hertz_duration"] = cf.duration;
        j["elastic_hertz_overlap"] = cf.overlap;
        j["elastic_hertz_force"] = cf.force;
        tc_ratio.push_back(r.duration / cf.duration);
        speeds.push(j);
      }
    });
  }
  summary["speed_sweep"] = speeds;
  write_quantity(h5, "/speed_sweep/speed", c.speeds, "mm us-1");
  write_quantity(h5, "/speed_sweep/restitution_exact_mapping", e_exact, "1");
  write_quantity(h5, "/speed_sweep/restitution_common_mapping", e_common, "1");
  write_quantity(h5, "/speed_sweep/duration_over_elastic_hertz", tc_ratio, "1");
  auto spread = [](const std::vector<double>& v) {
    return *std::max_element(v.begin(), v.end()) - *std::min_element(v.begin(), v.end());
  };
  double worst_exact = 0, worst_common = 0;
  for (size_t k = 0; k < e_exact.size(); ++k) {
    worst_exact = max_keep_nan(worst_exact, std::fabs(e_exact[k] - e_in));
    worst_common = max_keep_nan(worst_common, std::fabs(e_common[k] - e_in));
  }
  summary["restitution_error_exact_mapping"] = worst_exact;
  summary["restitution_error_common_mapping"] = worst_common;
  summary["restitution_speed_spread"] =
      spread(mats.damping == "restitution_exact" ? e_exact : e_common);
  std::cout << "restitution over speeds " << c.speeds.front() << " .. " << c.speeds.back()
            << ": input " << e_in << ", largest error exact mapping " << worst_exact
            << ", common mapping " << worst_common << "\n";
}

// 2. Oblique impacts at one speed over the incidence angles (with a snapshot series each).
void oblique_sweep(const ImpactScene& c, const ImpactPair& p, const RunOptions& opts, H5Writer& h5,
                   Json& summary) {
  const MaterialSet& mats = c.materials;
  const double estar = p.estar, rstar = p.rstar, mstar = p.mstar, mu = p.mu;
  const double v = c.oblique_speed;
  Json cases = Json::array();
  std::vector<double> angle, en, et, wout, rebound, jt_over_jn, cf_rebound, cf_wout, cf_et, sliding;
  with_material_model(mats, [&](const auto& model) {
    int k = 0;
    for (double a : c.angles) {
      SnapshotSeries snapshots(opts.out_dir, "snapshots_oblique_" + std::to_string(k),
                               c.snapshot_every);
      const ImpactResult r = run_case(model, c, v, a, true, estar, rstar, mstar, &snapshots);
      const double vn = r.vn_in, e = r.restitution_normal;
      // Gross sliding of a solid sphere on a wall (docs/model_dem.md §10): it slides for the
      // whole impact when |v_c| > (7/2) mu (1 + e) v_n; the tangential impulse is then
      // mu (1 + e) m v_n against the slip. For a pair the threshold involves both spheres'
      // inertia, so only the measured impulse ratio is reported.
      const double jn = r.impulse_normal;
      const double sgn = r.vc_in >= 0 ? 1.0 : -1.0;
      const bool slides = c.wall && std::fabs(r.vc_in) > 3.5 * mu * (1 + e) * vn;
      const double dvt = -sgn * mu * (1 + e) * vn;  // change of the centre's tangential speed
      const double vt_cf = r.vt_in + dvt;
      const double w_cf = r.spin_in - 2.5 * dvt / c.radius;  // torque lever -R z x f_t
      Json j = Json::object();
      j["angle_deg"] = a;
      j["restitution_normal"] = e;
      j["restitution_tangential"] = r.restitution_tangential;
      j["rebound_angle_deg"] = r.rebound_angle * 180 / M_PI;
      j["spin_in"] = r.spin_in;
      j["spin_out"] = r.spin_out;
      j["impulse_tangential_over_normal"] = jn != 0 ? -r.impulse_tangential / jn : 0.0;
      j["duration"] = r.duration;
      j["max_overlap"] = r.max_overlap;
      j["max_normal_force"] = r.max_normal_force;
      j["gross_sliding"] = slides;
      if (slides) {
        j["closed_form_impulse_ratio"] = sgn * mu;
        j["closed_form_spin_out"] = w_cf;
        j["closed_form_rebound_angle_deg"] = std::atan2(vt_cf, e * vn) * 180 / M_PI;
      }
      cases.push(j);
      angle.push_back(a), en.push_back(e), et.push_back(r.restitution_tangential);
      wout.push_back(r.spin_out * c.radius / v);
      rebound.push_back(r.rebound_angle * 180 / M_PI);
      jt_over_jn.push_back(jn != 0 ? -r.impulse_tangential / jn : 0.0);
      sliding.push_back(slides ? 1.0 : 0.0);
      cf_wout.push_back(slides ? w_cf * c.radius / v : NAN);
      cf_rebound.push_back(slides ? std::atan2(vt_cf, e * vn) * 180 / M_PI : NAN);
      cf_et.push_back(slides ? -(r.vc_in + 3.5 * dvt) / r.vc_in : NAN);  // v_c' = v_c + 7/2 dv_t
      const std::string g = "/oblique/case_" + std::to_string(k++);
      write_quantity(h5, g + "/time", r.t, "us");
      write_quantity(h5, g + "/overlap", r.overlap, "mm");
      write_quantity(h5, g + "/normal_force", r.force_normal, "N");
      write_quantity(h5, g + "/tangential_force", r.force_tangential, "N");
      h5.attribute(g, "angle_deg", a);
      std::cout << "angle " << a << " deg: e_n " << e << ", e_t " << r.restitution_tangential
                << ", rebound " << r.rebound_angle * 180 / M_PI << " deg, spin out " << r.spin_out
                << (slides ? " (gross sliding)" : "") << "\n";
    }
  });
  summary["oblique"] = cases;
  write_quantity(h5, "/angles/angle_deg", angle, "deg");
  write_quantity(h5, "/angles/restitution_normal", en, "1");
  write_quantity(h5, "/angles/restitution_tangential", et, "1");
  // Spins scaled by the sphere's radius over the oblique speed (omega R / v): pure numbers.
  write_quantity(h5, "/angles/spin_out_scaled", wout, "1");
  write_quantity(h5, "/angles/rebound_angle_deg", rebound, "deg");
  write_quantity(h5, "/angles/impulse_ratio", jt_over_jn, "1");
  write_quantity(h5, "/angles/gross_sliding", sliding, "1");
  write_quantity(h5, "/angles/closed_form_spin_out_scaled", cf_wout, "1");
  write_quantity(h5, "/angles/closed_form_rebound_angle_deg", cf_rebound, "deg");
  write_quantity(h5, "/angles/closed_form_restitution_tangential", cf_et, "1");
}

}  // namespace

void run_impact(const SceneFile& scene, const RunOptions& opts) {
  const ImpactScene c = read_scene(scene);
  if (!begin_outputs(opts)) return;
  const ImpactPair p = impact_pair(c);
  SceneOutput output(scene, opts, "impact");
  Json& summary = output.summary();
  summary["effective_young_modulus"] = p.estar;
  summary["effective_shear_modulus"] = c.materials.effective_shear(c.sphere, c.target);
  summary["reduced_radius"] = p.rstar;
  summary["reduced_mass"] = p.mstar;
  summary["restitution_input"] = p.e_in;
  summary["friction"] = p.mu;
  summary["alpha_exact"] = hertz_alpha_exact(p.e_in);
  summary["alpha_common"] = hertz_alpha_common(p.e_in);
  speed_sweep(c, p, output.h5(), summary);
  oblique_sweep(c, p, opts, output.h5(), summary);
  output.h5().attribute("/", "restitution_input", p.e_in);
  output.h5().attribute("/", "friction", p.mu);
  output.h5().attribute("/", "target", c.wall ? "wall" : "sphere");
  output.finish();
}

}  // namespace granular
