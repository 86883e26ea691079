// Scene `impact_benchmarks`: the eight single-contact benchmark tests of the DEM literature
// (Chung & Ooi, Granular Matter 13 (2011) 643-656) in one run, each against its closed form:
// elastic Hertz for the normal impacts (tests 1, 2), the input restitution (test 3), and
// rigid-body gross sliding for the oblique and spinning impacts (tests 4 to 8). A case is a
// table [cases.<name>] of the scene file: its two materials, the target (wall or sphere, with
// its own motion), and one swept quantity (docs/impact_benchmarks.md).
#include <Kokkos_Core.hpp>
#include <algorithm>
#include <cmath>
#include <iostream>
#include <string>
#include <tuple>
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

// What a case sweeps. speed: head-on impacts at each speed; restitution: head-on at `speed`
// with each input e; angle: resultant `speed` at each incidence angle (degrees);
// tangential_speed: normal `speed` with each tangential speed; spin: normal `speed` with each
// spin of the moving sphere (rad/us, about the axis normal to the plane of incidence).
enum class Sweep { Speed, Restitution, Angle, TangentialSpeed, Spin };

struct BenchCase {
  std::string name, title;
  long test = 0;
  Material sphere, target;
  bool wall = true;
  double radius = 1, target_radius = 1;
  Sweep sweep = Sweep::Speed;
  double speed = 0;
  std::vector<double> values;
  // The target sphere approaches with this normal speed and spins with this multiple of the
  // moving sphere's spin (test 7: two identical spheres, both moving, both spinning).
  double target_speed = 0, target_spin_ratio = 0;
};

struct BenchScene {
  std::vector<BenchCase> cases;
  MaterialSet contact;  // [contact] options only
  long steps_per_contact = 400;
};

Sweep read_sweep(const SceneFile& s, const std::string& key) {
  return s.choice(key, "angle", [](const std::string& v) {
    if (v == "speed") return Sweep::Speed;
    if (v == "restitution") return Sweep::Restitution;
    if (v == "angle") return Sweep::Angle;
    if (v == "tangential_speed") return Sweep::TangentialSpeed;
    if (v == "spin") return Sweep::Spin;
    throw InputError(
        "must be \"speed\", \"restitution\", \"angle\", \"tangential_speed\" or \"spin\"");
  });
}

BenchScene read_scene(const SceneFile& s) {
  BenchScene b;
  b.contact.read_contact(s);
  b.steps_per_contact = s.integer("run.steps_per_contact", 400);
  s.require(b.steps_per_contact >= 50 && b.steps_per_contact <= 1000000, "run.steps_per_contact",
            "must lie in [50, 1e6]");
  const auto names = s.tables("cases");
  s.require(!names.empty(), "cases", "needs at least one [cases.<name>] table");
  for (const std::string& name : names) {
    const std::string k = "cases." + name;
    BenchCase c;
    c.name = name;
    c.test = s.integer(k + ".test");
    c.title = s.text(k + ".title");
    c.sphere = Material::read(s, k + ".sphere", "sphere");
    const std::string target = s.text(k + ".target");
    s.require(target == "wall" || target == "sphere", k + ".target",
              "must be \"wall\" or \"sphere\"");
    c.wall = target == "wall";
    c.target = s.has(k + ".target_material") ? Material::read(s, k + ".target_material", "target")
                                             : c.sphere;
    c.target.name = "target";
    c.radius = 0.5 * s.real(k + ".diameter");
    c.target_radius = c.wall ? 0.0 : 0.5 * s.real(k + ".target_diameter", 2 * c.radius);
    c.sweep = read_sweep(s, k + ".sweep");
    c.speed = c.sweep == Sweep::Speed ? 1.0 : s.real(k + ".speed");  // speeds sweep: the values
    c.values = s.reals(k + ".values");
    c.target_speed = c.wall ? 0.0 : s.real(k + ".target_speed", 0.0);
    c.target_spin_ratio = c.wall ? 0.0 : s.real(k + ".target_spin_ratio", 0.0);
    s.require(c.test >= 1 && c.test <= 8, k + ".test", "must be a test number 1 to 8");
    s.require(c.radius > 0 && std::isfinite(c.radius), k + ".diameter",
              "must be positive and finite");
    s.require(c.wall || (c.target_radius > 0 && std::isfinite(c.target_radius)),
              k + ".target_diameter", "must be positive and finite");
    s.require(c.sphere.density > 0, k + ".sphere.density", "must be positive");
    s.require(!c.sphere.rigid(), k + ".sphere.young_modulus", "must be finite (a moving sphere)");
    s.require(c.wall || c.target.density > 0, k + ".target_material.density", "must be positive");
    s.require(c.speed > 0 && std::isfinite(c.speed), k + ".speed", "must be positive and finite");
    s.require(!c.values.empty() && c.values.size() <= 1000, k + ".values",
              "needs 1 to 1000 entries");
    for (double v : c.values) {
      s.require(std::isfinite(v), k + ".values", "must be finite numbers");
      if (c.sweep == Sweep::Speed) s.require(v > 0, k + ".values", "speeds must be positive");
      if (c.sweep == Sweep::Restitution)
        s.require(v > 0 && v <= 1, k + ".values", "restitutions must lie in (0, 1]");
      if (c.sweep == Sweep::Angle)
        s.require(v >= 0 && v < 90, k + ".values", "angles must lie in [0, 90) degrees");
    }
    s.require(std::isfinite(c.target_speed) && c.target_speed >= 0, k + ".target_speed",
              "must be finite and not negative");
    s.require(std::isfinite(c.target_spin_ratio), k + ".target_spin_ratio", "must be finite");
    b.cases.push_back(c);
  }
  s.reject_unknown_keys();
  return b;
}

// The two-material set of a case: the sphere in slot 0, the target (or wall) in slot 1.
MaterialSet case_materials(const BenchScene& b, const BenchCase& c, double restitution) {
  MaterialSet m = b.contact;
  m.materials = {c.sphere, c.target};
  if (restitution > 0) m.materials[0].restitution = m.materials[1].restitution = restitution;
  m.slot = {{"sphere", 0}, {"target", 1}};
  return m;
}

struct CaseOutput {
  std::vector<double> value, vn, vc, spin_in, mu, en, et, et_centre, spin_out, rebound_deg,
      impulse_ratio, duration, overlap, force, incidence;
  std::vector<double> cf_duration, cf_overlap, cf_force, cf_slides, cf_et, cf_spin, cf_rebound,
      cf_impulse, e_input;
};

double sphere_mass(const Material& m, double a) { return m.density * 4.0 / 3.0 * M_PI * a * a * a; }

// The impact of case c at swept value x: speeds, spins and time step as the sweep sets them.
ImpactSetup impact_setup(const BenchScene& b, const BenchCase& c, const MaterialSet& mats, double x,
                         double mstar, double rstar) {
  ImpactSetup s;
  s.wall = c.wall, s.wall_material = 1;
  s.radius1 = c.radius, s.density1 = c.sphere.density, s.species1 = 0;
  s.radius2 = c.target_radius, s.density2 = c.target.density, s.species2 = 1;
  // Relative normal and tangential speed of the centres, and the moving sphere's spin.
  double vn = c.speed, vt = 0.0, spin = 0.0;
  if (c.sweep == Sweep::Speed) vn = x;
  if (c.sweep == Sweep::Angle)
    vn = c.speed * std::cos(x * M_PI / 180), vt = c.speed * std::sin(x * M_PI / 180);
  if (c.sweep == Sweep::TangentialSpeed) vt = x;
  if (c.sweep == Sweep::Spin) spin = x;
  s.speed = std::hypot(vn, vt), s.angle = std::atan2(vt, vn);
  s.spin[1] = spin;
  if (!c.wall) {
    // The target rises towards the sphere above it: its approach adds to the relative
    // normal speed that `speed` and `angle` describe.
    s.target_velocity[2] = c.target_speed;
    s.target_spin[1] = c.target_spin_ratio * spin;
    s.speed = std::hypot(vn + c.target_speed, vt);
    s.angle = std::atan2(vt, vn + c.target_speed);
  }
  const double vn_rel = s.speed * std::cos(s.angle);
  s.dt = hertz_closed_form(mats.effective_young(0, 1), rstar, mstar, vn_rel).duration /
         b.steps_per_contact;
  s.dt_hint = "raise run.steps_per_contact (now " + std::to_string(b.steps_per_contact) + ")";
  return s;
}

// The largest departures of one case's impacts from the closed forms.
struct CaseErrors {
  double hertz = 0, restitution = 0, sliding = 0;
  int sliding_cases = 0;
};

// One case run: a row of columns per swept value, the errors, and its first impact's series.
struct CaseRun {
  CaseOutput o;
  CaseErrors err;
  ImpactResult first;
  double hertz_stiffness = 0;  // 4/3 E* sqrt(R*) of the first impact's pair
};

// Impact x of case c measured against the closed forms: its row of o and the errors.
void add_row(CaseOutput& o, CaseErrors& err, double x, double e_in, double mu,
             const ImpactResult& r, const HertzClosedForm& hz, const GrossSliding& g) {
  o.value.push_back(x);
  o.vn.push_back(r.vn_in), o.vc.push_back(r.vc_in), o.spin_in.push_back(r.spin_in);
  o.mu.push_back(mu);
  o.e_input.push_back(e_in);
  o.en.push_back(r.restitution_normal);
  o.et.push_back(r.restitution_tangential);
  o.et_centre.push_back(r.vt_in != 0 ? r.vt_out / r.vt_in : 0.0);
  o.spin_out.push_back(r.spin_out);
  o.rebound_deg.push_back(std::atan2(r.vc_out, r.vn_out) * 180 / M_PI);
  o.impulse_ratio.push_back(r.impulse_normal != 0 ? -r.impulse_tangential / r.impulse_normal : 0.0);
  o.duration.push_back(r.duration), o.overlap.push_back(r.max_overlap);
  o.force.push_back(r.max_normal_force);
  // Normalised incidence: the slip over what gross sliding removes in one impact.
  o.incidence.push_back(mu > 0 ? r.vc_in / (mu * (1 + r.restitution_normal) * r.vn_in) : 0.0);
  o.cf_duration.push_back(hz.duration), o.cf_overlap.push_back(hz.overlap);
  o.cf_force.push_back(hz.force);
  o.cf_slides.push_back(g.slides ? 1.0 : 0.0);
  const double nan = std::nan("");
  o.cf_et.push_back(g.slides ? g.restitution_tangential : nan);
  o.cf_spin.push_back(g.slides ? g.spin1_out : nan);
  o.cf_rebound.push_back(g.slides ? std::atan2(g.vc_out, r.vn_out) * 180 / M_PI : nan);
  o.cf_impulse.push_back(g.slides ? g.impulse_ratio : nan);
  if (e_in == 1.0 && r.vc_in == 0.0)
    err.hertz = max_keep_nan(err.hertz, std::max({std::fabs(r.duration / hz.duration - 1),
                                                  std::fabs(r.max_overlap / hz.overlap - 1),
                                                  std::fabs(r.max_normal_force / hz.force - 1)}));
  err.restitution = max_keep_nan(err.restitution, std::fabs(r.restitution_normal - e_in));
  if (g.slides && mu > 0) {
    ++err.sliding_cases;
    err.sliding = max_keep_nan(
        err.sliding,
        std::max({std::fabs(o.impulse_ratio.back() / g.impulse_ratio - 1),
                  std::fabs(r.spin_out - g.spin1_out) / std::max(std::fabs(g.spin1_out), 1e-300),
                  std::fabs(r.restitution_tangential - g.restitution_tangential)}));
  }
}

// Runs case c's impact at its iv-th value into `run` (the first one recorded step by step).
void run_impact_value(const BenchScene& b, const BenchCase& c, size_t iv, CaseRun& run) {
  const double x = c.values[iv];
  const double m1 = sphere_mass(c.sphere, c.radius);
  const double m2 = c.wall ? 0.0 : sphere_mass(c.target, c.target_radius);
  const double mstar = c.wall ? m1 : m1 * m2 / (m1 + m2);
  const double rstar =
      c.wall ? c.radius : c.radius * c.target_radius / (c.radius + c.target_radius);
  const MaterialSet mats = case_materials(b, c, c.sweep == Sweep::Restitution ? x : 0.0);
  const double estar = mats.effective_young(0, 1);
  const double e_in = mats.restitution(0, 1);
  const double mu =
      mats.tangential ? mats.pair(mats.materials[0].friction, mats.materials[1].friction) : 0.0;
  ImpactSetup s = impact_setup(b, c, mats, x, mstar, rstar);
  s.record = iv == 0;
  ImpactResult r;
  with_material_model(
      mats, [&](const auto& model) { r = impact<Kokkos::DefaultExecutionSpace>(model, s); });
  const auto hz = hertz_closed_form(estar, rstar, mstar, r.vn_in);
  const GrossSliding g = gross_sliding(m1, c.radius, mstar, r.vn_in, r.vt_in, r.spin_in, r.vc_in,
                                       mu, r.restitution_normal);
  add_row(run.o, run.err, x, e_in, mu, r, hz, g);
  if (s.record) {
    run.hertz_stiffness = 4.0 / 3.0 * estar * std::sqrt(rstar);
    run.first = std::move(r);
  }
}

const char* const kSweepNames[] = {"speed", "restitution", "angle", "tangential_speed", "spin"};

// Group /cases/<name> of results.h5: one column per measured and closed-form quantity.
void write_case_group(H5Writer& h5, const BenchCase& c, const CaseOutput& o) {
  const std::string g = "/cases/" + c.name;
  // The unit of `value`, the swept quantity (as read from the scene file).
  static const char* sweep_units[] = {"mm us-1", "1", "deg", "mm us-1", "rad us-1"};
  const std::tuple<const char*, const std::vector<double>*, const char*> columns[] = {
      {"value", &o.value, sweep_units[static_cast<int>(c.sweep)]},
      {"restitution_input", &o.e_input, "1"},
      {"normal_speed", &o.vn, "mm us-1"},
      {"slip_in", &o.vc, "mm us-1"},
      {"spin_in", &o.spin_in, "rad us-1"},
      {"friction", &o.mu, "1"},
      {"restitution_normal", &o.en, "1"},
      {"restitution_tangential", &o.et, "1"},
      {"restitution_tangential_centre", &o.et_centre, "1"},
      {"spin_out", &o.spin_out, "rad us-1"},
      {"rebound_angle_deg", &o.rebound_deg, "deg"},
      {"impulse_ratio", &o.impulse_ratio, "1"},
      {"duration", &o.duration, "us"},
      {"max_overlap", &o.overlap, "mm"},
      {"max_normal_force", &o.force, "N"},
      {"normalised_incidence", &o.incidence, "1"},
      {"hertz_duration", &o.cf_duration, "us"},
      {"hertz_overlap", &o.cf_overlap, "mm"},
      {"hertz_force", &o.cf_force, "N"},
      {"gross_sliding", &o.cf_slides, "1"},
      {"closed_form_restitution_tangential", &o.cf_et, "1"},
      {"closed_form_spin_out", &o.cf_spin, "rad us-1"},
      {"closed_form_rebound_angle_deg", &o.cf_rebound, "deg"},
      {"closed_form_impulse_ratio", &o.cf_impulse, "1"}};
  for (const auto& [name, col, unit] : columns) write_quantity(h5, g + "/" + name, *col, unit);
  h5.attribute(g, "test", static_cast<double>(c.test));
  h5.attribute(g, "title", c.title);
  h5.attribute(g, "sweep", kSweepNames[static_cast<int>(c.sweep)]);
  h5.attribute(g, "target", c.wall ? "wall" : "sphere");
  h5.attribute(g, "radius", c.radius);
}

// Case c in summary.json.
Json case_json(const BenchCase& c, const CaseErrors& err) {
  const bool hertz = c.sweep == Sweep::Speed || c.sweep == Sweep::Restitution;
  Json j = Json::object();
  j["name"] = c.name;
  j["test"] = c.test;
  j["title"] = c.title;
  j["sweep"] = kSweepNames[static_cast<int>(c.sweep)];
  j["cases"] = static_cast<long>(c.values.size());
  j["largest_restitution_error"] = err.restitution;
  if (hertz) j["largest_elastic_hertz_error"] = err.hertz;
  j["gross_sliding_cases"] = static_cast<long>(err.sliding_cases);
  if (err.sliding_cases > 0) j["largest_gross_sliding_error"] = err.sliding;
  return j;
}

// Case c's line on the console, once its impacts are done.
void report_case(const BenchCase& c, const CaseErrors& err) {
  const bool hertz = c.sweep == Sweep::Speed || c.sweep == Sweep::Restitution;
  std::cout << "test " << c.test << " " << c.name << ": " << c.values.size()
            << " impacts, restitution error " << err.restitution;
  if (hertz) std::cout << ", elastic Hertz error " << err.hertz;
  if (err.sliding_cases > 0)
    std::cout << ", gross sliding error " << err.sliding << " (" << err.sliding_cases
              << " sliding)";
  std::cout << "\n";
}

// Every case, every swept value.
std::vector<CaseRun> run_cases(const BenchScene& b) {
  std::vector<CaseRun> runs;
  for (const BenchCase& c : b.cases) {
    CaseRun run;
    for (size_t iv = 0; iv < c.values.size(); ++iv) run_impact_value(b, c, iv, run);
    report_case(c, run.err);
    runs.push_back(std::move(run));
  }
  return runs;
}

// Each case's first impact and columns in results.h5, its errors in the summary.
void write_cases(SceneOutput& output, const BenchScene& b, const std::vector<CaseRun>& runs) {
  H5Writer& h5 = output.h5();
  Json& summary = output.summary();
  summary["coulomb_limit"] =
      "mu |f_n| of the total normal force (elastic + dashpot), as docs/model_dem.md §3 writes it";
  Json cases = Json::array();
  for (size_t n = 0; n < runs.size(); ++n) {
    const BenchCase& c = b.cases[n];
    const ImpactResult& r = runs[n].first;
    const std::string g0 = "/cases/" + c.name + "/first";
    write_quantity(h5, g0 + "/time", r.t, "us");
    write_quantity(h5, g0 + "/overlap", r.overlap, "mm");
    write_quantity(h5, g0 + "/normal_force", r.force_normal, "N");
    write_quantity(h5, g0 + "/tangential_force", r.force_tangential, "N");
    write_quantity(h5, g0 + "/slip", r.slip, "mm us-1");
    h5.attribute(g0, "hertz_stiffness", runs[n].hertz_stiffness);
    write_case_group(h5, c, runs[n].o);
    cases.push(case_json(c, runs[n].err));
  }
  summary["cases"] = cases;
}

}  // namespace

void run_impact_benchmarks(const SceneFile& scene, const RunOptions& opts) {
  const BenchScene b = read_scene(scene);
  if (!begin_outputs(opts)) return;
  SceneOutput output(scene, opts, "impact_benchmarks");
  write_cases(output, b, run_cases(b));
  output.finish();
}

}  // namespace granular
