// Scene `impact`: single-contact verification. A sphere hits a wall or a sphere at rest at
// a list of incidence angles (and a list of speeds for head-on impacts), with any initial
// spin and any pair of materials (Hertz-Mindlin with restitution damping). Each case is
// reported next to its closed form where one exists: elastic Hertz duration, overlap and
// force; gross sliding (tangential impulse mu (1 + e) times the normal one, spin change,
// rebound angle); the restitution against the input one over the speeds, for the chosen
// mapping of e to the damping constant and for the other one.
#include <Kokkos_Core.hpp>
#include <algorithm>
#include <cmath>
#include <iostream>
#include <string>
#include <utility>
#include <vector>

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

// One head-on impact of the speed sweep under the scene's mapping, beside elastic Hertz.
struct SpeedRow {
  double speed = 0, restitution = 0, duration = 0, max_overlap = 0, max_normal_force = 0;
  HertzClosedForm hertz;
};

// 1. Head-on impacts over the speeds, with both mappings of e to the damping constant.
struct SpeedSweep {
  std::vector<SpeedRow> rows;                       // the scene's own mapping
  std::vector<double> e_exact, e_common, tc_ratio;  // per speed
  double worst_exact = 0, worst_common = 0, spread = 0;
};

SpeedSweep speed_sweep(const ImpactScene& c, const ImpactPair& p) {
  const MaterialSet& mats = c.materials;
  const double estar = p.estar, rstar = p.rstar, mstar = p.mstar, e_in = p.e_in;
  SpeedSweep w;
  for (const std::string& mapping :
       {std::string("restitution_exact"), std::string("restitution_common")}) {
    MaterialSet m = mats;
    m.damping = mapping;
    with_material_model(m, [&](const auto& model) {
      for (double v : c.speeds) {
        const ImpactResult r = run_case(model, c, v, 0.0, false, estar, rstar, mstar);
        (mapping == "restitution_exact" ? w.e_exact : w.e_common).push_back(r.restitution_normal);
        if (mapping != mats.damping) continue;
        const auto cf = hertz_closed_form(estar, rstar, mstar, v);
        w.rows.push_back(
            {v, r.restitution_normal, r.duration, r.max_overlap, r.max_normal_force, cf});
        w.tc_ratio.push_back(r.duration / cf.duration);
      }
    });
  }
  const std::vector<double>& own = mats.damping == "restitution_exact" ? w.e_exact : w.e_common;
  w.spread = *std::max_element(own.begin(), own.end()) - *std::min_element(own.begin(), own.end());
  for (size_t k = 0; k < w.e_exact.size(); ++k) {
    w.worst_exact = max_keep_nan(w.worst_exact, std::fabs(w.e_exact[k] - e_in));
    w.worst_common = max_keep_nan(w.worst_common, std::fabs(w.e_common[k] - e_in));
  }
  std::cout << "restitution over speeds " << c.speeds.front() << " .. " << c.speeds.back()
            << ": input " << e_in << ", largest error exact mapping " << w.worst_exact
            << ", common mapping " << w.worst_common << "\n";
  return w;
}

void write_speed_sweep(const ImpactScene& c, const SpeedSweep& w, H5Writer& h5, Json& summary) {
  Json speeds = Json::array();
  for (const SpeedRow& row : w.rows) {
    Json j = Json::object();
    j["speed"] = row.speed;
    j["restitution"] = row.restitution;
    j["duration"] = row.duration;
    j["max_overlap"] = row.max_overlap;
    j["max_normal_force"] = row.max_normal_force;
    j["elastic_hertz_duration"] = row.hertz.duration;
    j["elastic_hertz_overlap"] = row.hertz.overlap;
    j["elastic_hertz_force"] = row.hertz.force;
    speeds.push(j);
  }
  summary["speed_sweep"] = speeds;
  write_quantity(h5, "/speed_sweep/speed", c.speeds, "mm us-1");
  write_quantity(h5, "/speed_sweep/restitution_exact_mapping", w.e_exact, "1");
  write_quantity(h5, "/speed_sweep/restitution_common_mapping", w.e_common, "1");
  write_quantity(h5, "/speed_sweep/duration_over_elastic_hertz", w.tc_ratio, "1");
  summary["restitution_error_exact_mapping"] = w.worst_exact;
  summary["restitution_error_common_mapping"] = w.worst_common;
  summary["restitution_speed_spread"] = w.spread;
}

// One oblique impact, its series recorded, and gross sliding's closed form where it applies.
struct ObliqueCase {
  double angle = 0;
  ImpactResult r;
  bool slides = false;
  double sgn = 1, vt_cf = 0, w_cf = 0, dvt = 0;
};

// Gross sliding of a solid sphere on a wall (docs/model_dem.md §10): it slides for the whole
// impact when |v_c| > (7/2) mu (1 + e) v_n; the tangential impulse is then mu (1 + e) m v_n
// against the slip. For a pair the threshold involves both spheres' inertia, so only the
// measured impulse ratio is reported.
ObliqueCase oblique_case(const ImpactScene& c, double mu, double a, ImpactResult r) {
  ObliqueCase k;
  k.angle = a;
  const double vn = r.vn_in, e = r.restitution_normal;
  k.sgn = r.vc_in >= 0 ? 1.0 : -1.0;
  k.slides = c.wall && std::fabs(r.vc_in) > 3.5 * mu * (1 + e) * vn;
  k.dvt = -k.sgn * mu * (1 + e) * vn;  // change of the centre's tangential speed
  k.vt_cf = r.vt_in + k.dvt;
  k.w_cf = r.spin_in - 2.5 * k.dvt / c.radius;  // torque lever -R z x f_t
  k.r = std::move(r);
  return k;
}

// 2. Oblique impacts at one speed over the incidence angles (with a snapshot series each).
std::vector<ObliqueCase> oblique_sweep(const ImpactScene& c, const ImpactPair& p,
                                       const RunOptions& opts) {
  std::vector<ObliqueCase> cases;
  with_material_model(c.materials, [&](const auto& model) {
    int k = 0;
    for (double a : c.angles) {
      SnapshotSeries snapshots(opts.out_dir, "snapshots_oblique_" + std::to_string(k++),
                               c.snapshot_every);
      ObliqueCase o = oblique_case(
          c, p.mu, a,
          run_case(model, c, c.oblique_speed, a, true, p.estar, p.rstar, p.mstar, &snapshots));
      const ImpactResult& r = o.r;
      std::cout << "angle " << a << " deg: e_n " << r.restitution_normal << ", e_t "
                << r.restitution_tangential << ", rebound " << r.rebound_angle * 180 / M_PI
                << " deg, spin out " << r.spin_out << (o.slides ? " (gross sliding)" : "") << "\n";
      cases.push_back(std::move(o));
    }
  });
  return cases;
}

Json oblique_json(const ObliqueCase& k, double mu) {
  const ImpactResult& r = k.r;
  const double jn = r.impulse_normal, e = r.restitution_normal;
  Json j = Json::object();
  j["angle_deg"] = k.angle;
  j["restitution_normal"] = e;
  j["restitution_tangential"] = r.restitution_tangential;
  j["rebound_angle_deg"] = r.rebound_angle * 180 / M_PI;
  j["spin_in"] = r.spin_in;
  j["spin_out"] = r.spin_out;
  j["impulse_tangential_over_normal"] = jn != 0 ? -r.impulse_tangential / jn : 0.0;
  j["duration"] = r.duration;
  j["max_overlap"] = r.max_overlap;
  j["max_normal_force"] = r.max_normal_force;
  j["gross_sliding"] = k.slides;
  if (k.slides) {
    j["closed_form_impulse_ratio"] = k.sgn * mu;
    j["closed_form_spin_out"] = k.w_cf;
    j["closed_form_rebound_angle_deg"] = std::atan2(k.vt_cf, e * r.vn_in) * 180 / M_PI;
  }
  return j;
}

// The oblique impacts' series (/oblique/case_<k>) and table (/angles), and the summary's list.
void write_oblique(const ImpactScene& c, double mu, const std::vector<ObliqueCase>& cases,
                   H5Writer& h5, Json& summary) {
  const double v = c.oblique_speed;
  Json list = Json::array();
  std::vector<double> angle, en, et, wout, rebound, jt_over_jn, cf_rebound, cf_wout, cf_et, sliding;
  for (size_t k = 0; k < cases.size(); ++k) {
    const ObliqueCase& o = cases[k];
    const ImpactResult& r = o.r;
    const double vn = r.vn_in, e = r.restitution_normal, jn = r.impulse_normal;
    list.push(oblique_json(o, mu));
    angle.push_back(o.angle), en.push_back(e), et.push_back(r.restitution_tangential);
    wout.push_back(r.spin_out * c.radius / v);
    rebound.push_back(r.rebound_angle * 180 / M_PI);
    jt_over_jn.push_back(jn != 0 ? -r.impulse_tangential / jn : 0.0);
    sliding.push_back(o.slides ? 1.0 : 0.0);
    cf_wout.push_back(o.slides ? o.w_cf * c.radius / v : NAN);
    cf_rebound.push_back(o.slides ? std::atan2(o.vt_cf, e * vn) * 180 / M_PI : NAN);
    // v_c' = v_c + 7/2 dv_t
    cf_et.push_back(o.slides ? -(r.vc_in + 3.5 * o.dvt) / r.vc_in : NAN);
    const std::string g = "/oblique/case_" + std::to_string(k);
    write_quantity(h5, g + "/time", r.t, "us");
    write_quantity(h5, g + "/overlap", r.overlap, "mm");
    write_quantity(h5, g + "/normal_force", r.force_normal, "N");
    write_quantity(h5, g + "/tangential_force", r.force_tangential, "N");
    h5.attribute(g, "angle_deg", o.angle);
  }
  summary["oblique"] = list;
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

// The pair's constants in the summary.
void write_pair(const ImpactScene& c, const ImpactPair& p, Json& summary) {
  summary["effective_young_modulus"] = p.estar;
  summary["effective_shear_modulus"] = c.materials.effective_shear(c.sphere, c.target);
  summary["reduced_radius"] = p.rstar;
  summary["reduced_mass"] = p.mstar;
  summary["restitution_input"] = p.e_in;
  summary["friction"] = p.mu;
  summary["alpha_exact"] = hertz_alpha_exact(p.e_in);
  summary["alpha_common"] = hertz_alpha_common(p.e_in);
}

}  // namespace

void run_impact(const SceneFile& scene, const RunOptions& opts) {
  const ImpactScene c = read_scene(scene);
  if (!begin_outputs(opts)) return;
  const ImpactPair p = impact_pair(c);
  SceneOutput output(scene, opts, "impact");
  const SpeedSweep speeds = speed_sweep(c, p);
  const std::vector<ObliqueCase> oblique = oblique_sweep(c, p, opts);
  H5Writer& h5 = output.h5();
  write_pair(c, p, output.summary());
  write_speed_sweep(c, speeds, h5, output.summary());
  write_oblique(c, p.mu, oblique, h5, output.summary());
  h5.attribute("/", "restitution_input", p.e_in);
  h5.attribute("/", "friction", p.mu);
  h5.attribute("/", "target", c.wall ? "wall" : "sphere");
  output.finish();
}

}  // namespace granular
